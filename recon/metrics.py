"""Error measures between estimated and true spectra.

References
----------
- The thesis, Eq. 6.8: the mean relative error in percent,
  :math:`\\Upsilon_{rel}(x, y) = \\frac{100}{k} \\sum_i \\frac{|x_i - y_i|}{|x_i| + \\epsilon}`,
  with :math:`\\epsilon = 10^{-3}`.
- The thesis, section 6.2 (text after Eq. 6.7): :math:`\\Delta E^*_{94}` averaged over the CIE
  illuminants A, D65, D50, D75, FL1, FL4, FL8, FL12, HP1 and HP3.
- CIE 116-1995. Industrial colour-difference evaluation (the :math:`\\Delta E^*_{94}` formula).
- Kruse, F. A., et al. (1993). The spectral image processing system (SIPS). Remote Sensing of
  Environment, 44(2-3), 145-163. doi:10.1016/0034-4257(93)90013-N (the spectral angle).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from functools import lru_cache

import colour
import numpy as np

from recon.errors import InputError
from recon.spectra import WavelengthGrid

__all__ = [
    "THESIS_ILLUMINANTS",
    "THESIS_SET",
    "delta_e94",
    "peak_relative_rmse",
    "relative_error",
    "rmse",
    "spectral_angle",
]

THESIS_ILLUMINANTS: tuple[str, ...] = (
    "A",
    "D65",
    "D50",
    "D75",
    "FL1",
    "FL4",
    "FL8",
    "FL12",
    "HP1",
    "HP3",
)
"""CIE illuminants over which the thesis averages :math:`\\Delta E^*_{94}` (section 6.2)."""
THESIS_SET = THESIS_ILLUMINANTS  # the name used by the stable entry points

OBSERVER = "CIE 1931 2 Degree Standard Observer"
"""The colour-matching functions of :func:`delta_e94` (a key of ``colour.MSDS_CMFS``)."""


def relative_error(estimate: np.ndarray, truth: np.ndarray, eps: float = 1e-3) -> np.ndarray:
    """Per-spectrum mean relative error in percent (Eq. 6.8), band axis last.

    ``truth`` is the reference :math:`x` of Eq. 6.8; ``eps`` down-weights dark, noisy values.
    """
    estimate, truth = np.asarray(estimate, np.float64), np.asarray(truth, np.float64)
    if estimate.shape != truth.shape:
        raise InputError(
            f"relative_error: estimate {estimate.shape} and truth {truth.shape} differ in shape"
        )
    if not eps > 0:
        raise InputError(f"eps: expected a positive constant, got {eps}")
    return 100.0 * np.mean(np.abs(estimate - truth) / (np.abs(truth) + eps), axis=-1)


def peak_relative_rmse(
    estimate: np.ndarray, truth: np.ndarray, *, fit_scale: bool = True
) -> np.ndarray:
    """Per-column RMSE of ``(K, n)`` curves as a fraction of the true peak.

    With ``fit_scale`` the estimate is first multiplied by the least-squares global factor
    (one for all columns): for camera responses, whose overall scale a photograph cannot fix.
    """
    estimate, truth = np.asarray(estimate, np.float64), np.asarray(truth, np.float64)
    if estimate.shape != truth.shape:
        raise InputError(
            f"peak_relative_rmse: estimate {estimate.shape} and truth {truth.shape} differ in shape"
        )
    scale = np.sum(estimate * truth) / np.sum(estimate * estimate) if fit_scale else 1.0
    return np.sqrt(np.mean((scale * estimate - truth) ** 2, axis=0)) / np.abs(truth).max()


def _spectra_pair(
    estimate: np.ndarray, truth: np.ndarray, what: str
) -> tuple[np.ndarray, np.ndarray]:
    """Both inputs as float64 of one shape ``(..., K)``, finite; raise naming ``what`` if not."""
    estimate, truth = np.asarray(estimate, np.float64), np.asarray(truth, np.float64)
    if estimate.shape != truth.shape:
        raise InputError(
            f"{what}: estimate {estimate.shape} and truth {truth.shape} differ in shape"
        )
    if estimate.ndim == 0 or estimate.shape[-1] < 1:
        raise InputError(
            f"{what}: expected spectra of shape (..., K) with K >= 1, got shape {estimate.shape}"
        )
    for name, values in (("estimate", estimate), ("truth", truth)):
        if not np.all(np.isfinite(values)):
            raise InputError(f"{what}: {name} contains NaN or infinity; expected finite spectra")
    return estimate, truth


def rmse(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-spectrum root-mean-square error over the band axis (last).

    :math:`\\sqrt{\\frac{1}{k} \\sum_i (y_i - x_i)^2}`, in the units of the spectra.

    Parameters
    ----------
    estimate, truth
        Spectra ``(..., K)`` of one shape, finite.

    Returns
    -------
    numpy.ndarray
        ``(...)``.

    Examples
    --------
    >>> float(rmse(np.array([1.0, 1.0]), np.array([0.0, 0.0])))
    1.0
    """
    estimate, truth = _spectra_pair(estimate, truth, "rmse")
    return np.sqrt(np.mean((estimate - truth) ** 2, axis=-1))


def spectral_angle(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-spectrum angle in degrees between the spectra as K-vectors (spectral angle mapper).

    The angle ignores the spectra's scale: a spectrum and any positive multiple of it are 0
    degrees apart. It is computed as :math:`2 \\arctan(\\|\\hat y - \\hat x\\| /
    \\|\\hat y + \\hat x\\|)` with unit vectors :math:`\\hat x, \\hat y`, which stays accurate near
    0 degrees where :math:`\\arccos` of the normalized dot product does not.

    Zero vectors have no direction; by definition here two zero spectra are 0 degrees apart
    (they are identical) and a zero spectrum is 90 degrees from any non-zero one (nothing in
    common; the largest angle that non-negative spectra can have).

    Parameters
    ----------
    estimate, truth
        Spectra ``(..., K)`` of one shape, finite.

    Returns
    -------
    numpy.ndarray
        ``(...)`` in degrees, in [0, 180].

    Examples
    --------
    >>> float(spectral_angle(np.array([1.0, 0.0]), np.array([0.0, 2.0])))
    90.0
    """
    estimate, truth = _spectra_pair(estimate, truth, "spectral_angle")
    norm_estimate = np.linalg.norm(estimate, axis=-1, keepdims=True)
    norm_truth = np.linalg.norm(truth, axis=-1, keepdims=True)
    zero_estimate, zero_truth = norm_estimate[..., 0] == 0, norm_truth[..., 0] == 0
    unit_estimate = estimate / np.where(norm_estimate == 0, 1.0, norm_estimate)
    unit_truth = truth / np.where(norm_truth == 0, 1.0, norm_truth)
    angle = 2.0 * np.arctan2(
        np.linalg.norm(unit_estimate - unit_truth, axis=-1),
        np.linalg.norm(unit_estimate + unit_truth, axis=-1),
    )
    degrees = np.degrees(angle)
    degrees = np.where(zero_estimate != zero_truth, 90.0, degrees)
    return np.where(zero_estimate & zero_truth, 0.0, degrees)


def _regular_shape(wavelengths: np.ndarray) -> colour.SpectralShape:
    """The ``colour.SpectralShape`` of a regular grid; raise for an irregular one."""
    steps = np.diff(wavelengths)
    if not np.allclose(steps, steps[0], rtol=1e-9, atol=1e-9):
        raise InputError(
            f"wavelengths_nm: delta_e94 needs a regular grid (constant step), got steps from "
            f"{steps.min():g} to {steps.max():g} nm; resample with recon.spectra.resample"
        )
    shape = colour.SpectralShape(wavelengths[0], wavelengths[-1], steps[0])
    if shape.wavelengths.size != wavelengths.size or not np.allclose(
        shape.wavelengths, wavelengths, rtol=0, atol=1e-6
    ):
        raise InputError(
            f"wavelengths_nm: could not describe the grid {wavelengths[0]:g}-{wavelengths[-1]:g} "
            f"nm in {steps[0]:g} nm steps as a colour.SpectralShape"
        )
    return shape


@lru_cache(maxsize=64)
def _xyz_weighting(wavelengths: tuple[float, ...], illuminant: str) -> np.ndarray:
    """``(K, 3)`` matrix W with ``XYZ = reflectance @ W`` under ``illuminant`` (white Y = 100).

    Row ``i`` is colour's own *Integration* tristimulus value of the unit impulse at band ``i``
    (``colour.sd_to_XYZ`` is linear in the reflectance), so ``reflectance @ W`` equals
    ``colour.sd_to_XYZ(reflectance, cmfs, illuminant, method="Integration", shape=...)``: the
    CMFs and the illuminant are aligned to the grid by colour (interpolated, and extrapolated
    as constants beyond their tabulated range), :math:`X = k \\sum_i R_i S_i \\bar x_i
    \\Delta\\lambda`, :math:`k = 100 / \\sum_i S_i \\bar y_i \\Delta\\lambda`.
    """
    grid = np.asarray(wavelengths, np.float64)
    shape = _regular_shape(grid)
    with warnings.catch_warnings():
        # colour announces that it aligns the CMFs and the illuminant to the grid: intended.
        warnings.simplefilter("ignore", colour.utilities.ColourRuntimeWarning)
        weighting = colour.sd_to_XYZ(
            np.eye(grid.size),
            colour.MSDS_CMFS[OBSERVER],
            colour.SDS_ILLUMINANTS[illuminant],
            method="Integration",
            shape=shape,
        )
    weighting = np.asarray(weighting, np.float64)
    weighting.setflags(write=False)
    return weighting


def delta_e94(
    estimate: np.ndarray,
    truth: np.ndarray,
    wavelengths_nm: np.ndarray | WavelengthGrid,
    illuminants: Sequence[str] | str = THESIS_ILLUMINANTS,
) -> np.ndarray:
    """Per-spectrum CIE 1994 colour difference, averaged over illuminants (thesis section 6.2).

    The thesis evaluates :math:`\\Upsilon_{\\Delta E} = \\Delta E^*_{94}` "for a set of selected
    CIE lamps covering a broad range of everyday illumination conditions (A, D65, D50, D75, FL1,
    FL4, FL8, FL12, HP1, HP3)" and averages the single values (text after Eq. 6.7). For each
    illuminant the reflectance spectra become CIE XYZ with the CIE 1931 2 degree observer
    (colour's *Integration* method on the given grid, scaled so that the perfect reflector has
    Y = 100), then CIE L*a*b* relative to the XYZ of the perfect reflector under that
    illuminant, then :math:`\\Delta E^*_{94}` (graphic-arts weights, ``colour.delta_E`` with
    ``method="CIE 1994"``) with ``truth`` as the reference (the formula is not symmetric: its
    chroma weighting uses the reference's chroma).

    Parameters
    ----------
    estimate, truth
        Reflectance spectra ``(..., K)`` of one shape on ``wavelengths_nm``, finite; values of
        about [0, 1] (1 = perfect white). Negative values are allowed (estimates may have them).
    wavelengths_nm
        The ``K`` band wavelengths in nm (or a ``WavelengthGrid``); they must be regularly
        spaced (e.g. ``DEFAULT_GRID``), as colour's integration assumes.
    illuminants
        Keys of ``colour.SDS_ILLUMINANTS``; default :data:`THESIS_ILLUMINANTS`. A single name
        gives the difference under that illuminant alone.

    Returns
    -------
    numpy.ndarray
        ``(...)``, the mean over the illuminants of :math:`\\Delta E^*_{94}`.

    Notes
    -----
    A ``(K, 3)`` weighting matrix is computed once per grid and illuminant (and cached); the
    matrices of all illuminants are stacked, so the cost is one matrix product per input plus
    colour's vectorized Lab and :math:`\\Delta E` conversions (about 0.5 s for
    :math:`10^5` spectra and the ten thesis illuminants).

    Examples
    --------
    >>> from recon.spectra import DEFAULT_GRID
    >>> grey = np.full(33, 0.5)
    >>> float(delta_e94(grey, grey, DEFAULT_GRID))
    0.0
    """
    estimate, truth = _spectra_pair(estimate, truth, "delta_e94")
    grid = (
        wavelengths_nm
        if isinstance(wavelengths_nm, WavelengthGrid)
        else WavelengthGrid(wavelengths_nm)
    )
    if grid.size != truth.shape[-1]:
        raise InputError(
            f"wavelengths_nm: expected {truth.shape[-1]} wavelengths to match the band axis of "
            f"the spectra {truth.shape}, got {grid.size}"
        )
    names = (illuminants,) if isinstance(illuminants, str) else tuple(illuminants)
    if not names:
        raise InputError("illuminants: expected at least one illuminant name, got none")
    unknown = [name for name in names if name not in colour.SDS_ILLUMINANTS]
    if unknown:
        raise InputError(
            f"illuminants: {unknown} are not keys of colour.SDS_ILLUMINANTS (e.g. 'D65', 'FL4')"
        )
    key = tuple(float(wavelength) for wavelength in grid.wavelengths_nm)
    # One (K, n, 3) weighting for all illuminants: a single pass over each input.
    weighting = np.stack([_xyz_weighting(key, name) for name in names], axis=1)
    white_xy = colour.XYZ_to_xy(weighting.sum(axis=0))
    columns = weighting.reshape(grid.size, -1) / 100.0
    lab = []
    with colour.domain_range_scale("reference"):
        for spectra in (truth, estimate):
            xyz = (spectra.reshape(-1, grid.size) @ columns).reshape(-1, len(names), 3)
            lab.append(colour.XYZ_to_Lab(xyz, white_xy))
        difference = colour.delta_E(lab[0], lab[1], method="CIE 1994")
    return np.mean(difference, axis=-1).reshape(truth.shape[:-1])
