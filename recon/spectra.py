"""Wavelength grids and sampled spectra: the spectral vocabulary of spectwin.

Every array that carries spectra carries its grid (``SampledSpectra``); spectra on different
grids are never combined implicitly, they are resampled explicitly with :func:`resample` and a
stated out-of-range policy. Band integrals (:func:`band_integrals`) are the discrete form of the
camera model integral :math:`c_k = \\int L(\\lambda) S_k(\\lambda) d\\lambda` that underlies thesis
Eq. 6.1 and Eq. 10.9, computed with trapezoidal quadrature weights of the grid.

The default grid is the LCTF grid of the thesis (section 3.2.2): 400 to 720 nm in 10 nm steps,
33 bands.

References
----------
- The thesis, section 3.2.2 (VariSpec band centres 400-720 nm, 10 nm steps) and Eq. 6.1.
- Fritsch, F. N., & Carlson, R. E. (1980). Monotone Piecewise Cubic Interpolation. SIAM Journal
  on Numerical Analysis, 17(2), 238-246. doi:10.1137/0717021 (the ``"pchip"`` method).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import colour
import numpy as np
from scipy import integrate, interpolate

from recon.errors import InputError

__all__ = [
    "DEFAULT_GRID",
    "OutOfRangePolicy",
    "ResampleMethod",
    "SampledSpectra",
    "WavelengthGrid",
    "band_integrals",
    "from_colour",
    "resample",
    "to_colour",
]

OutOfRangePolicy = Literal["error", "zero", "clamp"]
ResampleMethod = Literal["linear", "pchip", "box"]


@dataclass(frozen=True, eq=False)
class WavelengthGrid:
    """Strictly increasing sample wavelengths in nm (float64, read-only).

    Parameters
    ----------
    wavelengths_nm
        One-dimensional, finite, positive and strictly increasing; at least two samples.

    Examples
    --------
    >>> WavelengthGrid.regular(400, 720, 10).size
    33
    """

    wavelengths_nm: np.ndarray

    def __post_init__(self) -> None:
        wavelengths = np.array(self.wavelengths_nm, dtype=np.float64)
        if wavelengths.ndim != 1 or wavelengths.size < 2:
            raise InputError(
                f"wavelengths_nm: expected a 1-D array of at least 2 samples, got shape "
                f"{wavelengths.shape}"
            )
        if not np.all(np.isfinite(wavelengths)) or wavelengths[0] <= 0:
            raise InputError("wavelengths_nm: expected finite, positive wavelengths in nm")
        steps = np.diff(wavelengths)
        if np.any(steps <= 0):
            bad = int(np.argmax(steps <= 0))
            raise InputError(
                f"wavelengths_nm: expected strictly increasing wavelengths, but sample {bad + 1} "
                f"({wavelengths[bad + 1]:g} nm) does not exceed sample {bad} "
                f"({wavelengths[bad]:g} nm)"
            )
        wavelengths.setflags(write=False)
        object.__setattr__(self, "wavelengths_nm", wavelengths)

    @classmethod
    def regular(cls, start_nm: float, stop_nm: float, step_nm: float) -> WavelengthGrid:
        """Regular grid from ``start_nm`` to ``stop_nm`` inclusive in steps of ``step_nm``."""
        if not step_nm > 0 or not stop_nm > start_nm:
            raise InputError(
                f"regular grid: expected start < stop and step > 0, got start={start_nm}, "
                f"stop={stop_nm}, step={step_nm}"
            )
        count = (stop_nm - start_nm) / step_nm
        if abs(count - round(count)) > 1e-9 * max(1.0, count):
            raise InputError(
                f"regular grid: (stop - start) / step must be an integer, got {count:g}"
            )
        return cls(start_nm + step_nm * np.arange(round(count) + 1))

    @property
    def size(self) -> int:
        """Number of samples K."""
        return self.wavelengths_nm.size

    def __len__(self) -> int:
        return self.size

    @property
    def start_nm(self) -> float:
        return float(self.wavelengths_nm[0])

    @property
    def stop_nm(self) -> float:
        return float(self.wavelengths_nm[-1])

    def quadrature_weights(self) -> np.ndarray:
        """Trapezoidal weights :math:`w_i` in nm so that :math:`\\sum_i w_i f_i \\approx \\int f`.

        The integral runs over ``[start_nm, stop_nm]``: the end samples get half a step.
        """
        steps = np.diff(self.wavelengths_nm)
        weights = np.zeros(self.size)
        weights[:-1] += steps / 2
        weights[1:] += steps / 2
        return weights

    def __eq__(self, other: object) -> bool:
        return isinstance(other, WavelengthGrid) and np.array_equal(
            self.wavelengths_nm, other.wavelengths_nm
        )

    def __hash__(self) -> int:
        return hash(self.wavelengths_nm.tobytes())

    def describe(self) -> str:
        """Short human-readable description, e.g. ``'33 samples, 400-720 nm'``."""
        return f"{self.size} samples, {self.start_nm:g}-{self.stop_nm:g} nm"

    def __repr__(self) -> str:
        return f"WavelengthGrid({self.describe()})"


DEFAULT_GRID = WavelengthGrid.regular(400.0, 720.0, 10.0)
"""The LCTF grid of the thesis: 400-720 nm, 10 nm steps, 33 bands (section 3.2.2)."""


@dataclass(frozen=True, eq=False)
class SampledSpectra:
    """Spectra sampled on a grid: ``values`` of shape ``(..., K)`` with K = ``grid.size``.

    Parameters
    ----------
    grid
        The wavelengths of the last axis of ``values``.
    values
        Finite float64 array whose last axis matches the grid.
    names
        Optional labels of the rows when ``values`` is 2-D (e.g. ColorChecker patch names).
    """

    grid: WavelengthGrid
    values: np.ndarray
    names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.grid, WavelengthGrid):
            raise InputError(f"grid: expected a WavelengthGrid, got {type(self.grid)}")
        values = np.asarray(self.values, dtype=np.float64)
        if values.ndim == 0 or values.shape[-1] != self.grid.size:
            raise InputError(
                f"values: expected the last axis to match the grid ({self.grid.describe()}), got "
                f"shape {values.shape}"
            )
        if not np.all(np.isfinite(values)):
            raise InputError("values: expected finite spectra, found NaN or infinity")
        object.__setattr__(self, "values", values)
        if self.names is not None:
            names = tuple(str(name) for name in self.names)
            if values.ndim != 2 or len(names) != values.shape[0]:
                raise InputError(
                    f"names: expected one name per row of 2-D values, got {len(names)} names "
                    f"for values of shape {values.shape}"
                )
            object.__setattr__(self, "names", names)

    @property
    def wavelengths_nm(self) -> np.ndarray:
        return self.grid.wavelengths_nm

    def require_non_negative(self, what: str) -> SampledSpectra:
        """Return ``self``, or raise if any value is negative (for powers, reflectances, QE)."""
        if np.any(self.values < 0):
            index = np.unravel_index(np.argmin(self.values), self.values.shape)
            raise InputError(
                f"{what}: expected non-negative spectra, found {self.values[index]:g} at "
                f"{self.wavelengths_nm[index[-1]]:g} nm"
            )
        return self

    def row(self, name: str) -> SampledSpectra:
        """The single spectrum labelled ``name``."""
        if self.names is None or name not in self.names:
            raise InputError(f"name: expected one of {self.names}, got {name!r}")
        return SampledSpectra(self.grid, self.values[self.names.index(name)])

    def __mul__(self, other: SampledSpectra | float) -> SampledSpectra:
        """Product with a scalar or with spectra on the same grid (values broadcast)."""
        other_values: np.ndarray | float
        if isinstance(other, SampledSpectra):
            _require_same_grid(self.grid, other.grid, "product of spectra")
            other_values = other.values
            names = self.names if self.values.ndim >= other.values.ndim else other.names
        else:
            other_values, names = float(other), self.names
        return SampledSpectra(self.grid, self.values * other_values, names)

    __rmul__ = __mul__


def _require_same_grid(first: WavelengthGrid, second: WavelengthGrid, what: str) -> None:
    if first != second:
        raise InputError(
            f"{what}: grids differ ({first.describe()} vs {second.describe()}); resample one "
            f"explicitly with recon.spectra.resample"
        )


def _cell_edges(wavelengths: np.ndarray) -> np.ndarray:
    """Edges of the cells around each sample: midpoints, with symmetric end cells."""
    mid = (wavelengths[1:] + wavelengths[:-1]) / 2
    first = wavelengths[0] - (mid[0] - wavelengths[0])
    last = wavelengths[-1] + (wavelengths[-1] - mid[-1])
    return np.concatenate([[first], mid, [last]])


def _piecewise_linear_integral(
    wavelengths: np.ndarray, values: np.ndarray, at: np.ndarray, outside: OutOfRangePolicy
) -> np.ndarray:
    """Exact integral from ``wavelengths[0]`` to ``at`` of the piecewise-linear interpolant.

    Beyond the sampled range the spectrum is continued as zero (``outside="zero"``) or by its
    end values (otherwise).
    """
    steps = np.diff(wavelengths)
    cumulative = integrate.cumulative_trapezoid(values, wavelengths, axis=-1, initial=0.0)
    segment = np.clip(np.searchsorted(wavelengths, at, side="right") - 1, 0, wavelengths.size - 2)
    offset = np.clip(at, wavelengths[0], wavelengths[-1]) - wavelengths[segment]
    slope = (values[..., segment + 1] - values[..., segment]) / steps[segment]
    inside = cumulative[..., segment] + values[..., segment] * offset + 0.5 * slope * offset**2
    if outside == "zero":
        return inside
    below = np.minimum(at - wavelengths[0], 0.0) * values[..., :1]
    above = np.maximum(at - wavelengths[-1], 0.0) * values[..., -1:]
    return inside + below + above


def resample(
    spectra: SampledSpectra,
    grid: WavelengthGrid,
    *,
    method: ResampleMethod = "linear",
    out_of_range: OutOfRangePolicy = "error",
) -> SampledSpectra:
    """Resample spectra onto another grid.

    Parameters
    ----------
    spectra
        Source spectra.
    grid
        Target grid.
    method
        ``"linear"`` (piecewise-linear interpolation), ``"pchip"`` (shape-preserving cubic,
        Fritsch and Carlson 1980: no overshoot, so non-negative spectra stay non-negative), or
        ``"box"`` (the mean of the piecewise-linear source over each target sample's cell, which
        conserves integrals: use it to go from a fine to a coarse grid, e.g. for lamps with narrow
        emission lines).
    out_of_range
        What to do where the target grid leaves the source's range: ``"error"`` raises,
        ``"zero"`` treats the spectrum as zero there, ``"clamp"`` holds the end values.

    Returns
    -------
    SampledSpectra
        The spectra on ``grid``, names kept.

    Examples
    --------
    >>> fine = SampledSpectra(WavelengthGrid.regular(400, 720, 1), np.ones(321))
    >>> resample(fine, DEFAULT_GRID).values.shape
    (33,)
    """
    if method not in ("linear", "pchip", "box"):
        raise InputError(f"method: expected 'linear', 'pchip' or 'box', got {method!r}")
    if out_of_range not in ("error", "zero", "clamp"):
        raise InputError(f"out_of_range: expected 'error', 'zero' or 'clamp', got {out_of_range!r}")
    source = spectra.wavelengths_nm
    target = grid.wavelengths_nm
    outside = (target < source[0]) | (target > source[-1])
    if out_of_range == "error" and np.any(outside):
        raise InputError(
            f"resample: target grid ({grid.describe()}) leaves the source range "
            f"({spectra.grid.describe()}); pass out_of_range='zero' or 'clamp' to extend it"
        )
    if method == "box":
        edges = _cell_edges(target)
        integral = _piecewise_linear_integral(source, spectra.values, edges, out_of_range)
        values = np.diff(integral, axis=-1) / np.diff(edges)
    else:
        if method == "linear":
            interpolant = interpolate.make_interp_spline(source, spectra.values, k=1, axis=-1)
        else:
            interpolant = interpolate.PchipInterpolator(source, spectra.values, axis=-1)
        values = interpolant(np.clip(target, source[0], source[-1]))
        if out_of_range == "zero":
            values[..., outside] = 0.0
    return SampledSpectra(grid, values, spectra.names)


def band_integrals(spectra: SampledSpectra, responses: SampledSpectra) -> np.ndarray:
    """Band integrals :math:`c_k = \\int L(\\lambda) S_k(\\lambda) d\\lambda` (Eq. 6.1, Eq. 10.9).

    Parameters
    ----------
    spectra
        :math:`L`, values ``(..., K)``.
    responses
        :math:`S_k`, values ``(n_bands, K)`` or ``(K,)`` on the same grid.

    Returns
    -------
    numpy.ndarray
        ``(..., n_bands)`` (or ``(...)`` for a single response), in the product of the units of
        both inputs times nm. Uses trapezoidal weights over the grid's range: narrow features
        need a grid fine enough to resolve them.
    """
    _require_same_grid(spectra.grid, responses.grid, "band_integrals")
    weighted = spectra.values * spectra.grid.quadrature_weights()
    return weighted @ responses.values.T


def to_colour(
    spectra: SampledSpectra, name: str = "spectwin"
) -> colour.SpectralDistribution | colour.MultiSpectralDistributions:
    """Convert to ``colour.SpectralDistribution`` (1-D) or ``MultiSpectralDistributions`` (2-D)."""
    if spectra.values.ndim == 1:
        return colour.SpectralDistribution(spectra.values, spectra.wavelengths_nm, name=name)
    if spectra.values.ndim == 2:
        labels = spectra.names or tuple(str(i) for i in range(spectra.values.shape[0]))
        return colour.MultiSpectralDistributions(
            spectra.values.T, spectra.wavelengths_nm, name=name, labels=labels
        )
    raise InputError(f"to_colour: expected 1-D or 2-D values, got shape {spectra.values.shape}")


def from_colour(
    distribution: colour.SpectralDistribution | colour.MultiSpectralDistributions,
) -> SampledSpectra:
    """Convert a ``colour`` spectral distribution to ``SampledSpectra`` on its own wavelengths."""
    if isinstance(distribution, colour.MultiSpectralDistributions):
        return SampledSpectra(
            WavelengthGrid(distribution.wavelengths),
            np.asarray(distribution.values).T,
            tuple(distribution.labels),
        )
    if isinstance(distribution, colour.SpectralDistribution):
        return SampledSpectra(
            WavelengthGrid(distribution.wavelengths), np.asarray(distribution.values)
        )
    raise InputError(
        f"from_colour: expected a colour SpectralDistribution or MultiSpectralDistributions, got "
        f"{type(distribution)}"
    )
