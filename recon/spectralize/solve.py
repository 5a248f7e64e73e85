"""Spectralization: dense spectral images from dense RGB plus sparse or noisy spectral data.

The unknown spectral image :math:`S` (``n`` pixels over one or several images, ``K`` bands)
minimizes a linear least-squares energy (thesis Eq. 6.9, 10.1, 10.12)

.. math::
    E(S) = \\alpha\\, E_{data}(S) + \\beta \\sum_i \\lVert f_i S_i R_{cam} - f_i V_i \\rVert^2
         + \\gamma \\sum_i \\sum_{j \\in N_i} \\lVert f_i S_i - f_j S_j \\rVert^2
         + \\delta \\sum_i \\sum_{l<K} (f_i S_{i,l} - f_i S_{i,l+1})^2,

solved for the scaled image :math:`X_i = f_i S_i` with :math:`f_i = (\\sum_c V_i^c)^{-p_{dyn}}`
(Eq. 10.2; :math:`p_{dyn} = 0` gives Eq. 6.9/6.10). The data term is any mix of

- point spectra (whisk-broom or push-broom pixels, Eq. 6.10): :class:`PointSpectra`;
- noisy band images matched after a Gaussian filter (Eq. 10.1): :class:`BandImage`;
- general device integrals :math:`\\sum_{i,l} w_{i,l,j} S_{i,l} = D_j` (Eq. 6.9):
  :class:`DeviceIntegrals`.

The neighbours :math:`N_i` come from :mod:`recon.spectralize.appearance`. With
``prior="regression"`` the prior and smoothness terms act on :math:`X - B` instead, where
:math:`B_i = f_i V_i W` and :math:`W` is the least-squares map from camera values to the point
spectra (Hardeberg's inverse matrix, Sec. 6.1; :func:`build_problem`) or a map the caller gives
(``regression=``). The weights are
normalized by the number of terms (Eq. 6.11, or Eq. 10.13 with the smoothness term), so the primed
weights :class:`EnergyWeights` state the terms' relative importance (defaults
:math:`\\alpha' = \\beta' = \\gamma' = 1`; :math:`\\delta' = 0.1` with band images, 0 otherwise).

Solvers: ``"lsqr"`` and ``"lsmr"`` (scipy, matrix-free on the operator :math:`M_E` of Eq. 6.12,
as in the thesis) for any energy; ``"multigrid"`` (:mod:`recon.spectralize.kronecker`) when the
normal equations split as a Kronecker sum (point spectra, camera, prior and smoothness terms
only), which is exact and far faster; ``"auto"`` picks ``"multigrid"`` where it applies.

References
----------
- The thesis, chapter 6 (Eq. 6.3-6.12) and section 10.1 (Eq. 10.1, 10.2, 10.12, 10.13).
- Paige, C. C., & Saunders, M. A. (1982). LSQR: An algorithm for sparse linear equations and
  sparse least squares. ACM TOMS 8(1), 43-71.
- Shafer, S. A. (1985). Using color to separate reflection components. Color Research &
  Application 10(4), 210-218 (the dichromatic reflection model).
- Lee, H.-C., Breneman, E. J., & Schulte, C. P. (1990). Modeling light reflection for computer
  color vision. IEEE TPAMI 12(4), 402-409 (the neutral interface reflection).
- Fong, D. C.-L., & Saunders, M. (2011). LSMR: An iterative algorithm for sparse least-squares
  problems. SIAM J. Sci. Comput. 33(5), 2950-2971.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import sparse
from scipy.sparse import linalg
from threadpoolctl import threadpool_limits

from recon.errors import InputError
from recon.progress import progress_steps
from recon.spectra import SampledSpectra, WavelengthGrid
from recon.spectralize.appearance import (
    NeighbourGraph,
    appearance_neighbours,
    appearance_points,
    connect_components,
)
from recon.spectralize.energy import (
    AppearancePriorTerm,
    CameraTerm,
    DeviceIntegralTerm,
    FilteredBandTerm,
    PointSpectraTerm,
    SpectralSmoothnessTerm,
    gaussian_plane,
)
from recon.spectralize.kronecker import FactoredRhs, solve_kronecker_sum

__all__ = [
    "BandImage",
    "DeviceIntegrals",
    "DYNAMIC_FLOOR",
    "EnergyWeights",
    "PRIORS",
    "PointSpectra",
    "SpectralizationProblem",
    "SpectralizationResult",
    "build_problem",
    "dynamic_scale",
    "neighbour_graph",
    "reconstruct",
    "regression_prior",
    "spectralize",
]

SOLVERS = ("auto", "multigrid", "lsqr", "lsmr")
PRIORS = ("spectra", "regression")
DYNAMIC_FLOOR = 0.05
"""Smallest pixel sum :math:`\\sum_c V_i^c` that Eq. 10.2 scales by, as a fraction of the mean.

Noisy band images (Eq. 10.1) are compared after a Gaussian filter of the f-scaled values, so a
pixel's scale reaches its filtered neighbours: a black holder pixel at a floor of 0.1 % of the
mean scales its band noise by 1000 and spreads it into the targets of the lit pixels beside it.
On the case of :func:`recon.experiments.real_images.holder_bar_case` (a 96 px mosaic of VHREL
clothes with a black bar across it, nine 5 %-noisy band images filtered at 2 px) with
``p_dyn = 1``, the lit pixels beside the bar came out at 72.5 % (Eq. 6.8) with a floor of 0.1 %
and at 6.5 % with 5 % (4.9 % at ``p_dyn = 0``); BENCHMARKS.md,
"Spectralization on real spectra"."""
_PRIOR_TERMS = (AppearancePriorTerm, SpectralSmoothnessTerm)


@dataclass(frozen=True)
class PointSpectra:
    """Spectra known at some pixels (Eq. 6.10): ``pixels`` are flat indices into the
    ``(n_images, height, width)`` pixel grid (row-major), ``spectra`` is ``(m, K)``: an array,
    or ``SampledSpectra`` whose grid must equal the response's."""

    pixels: np.ndarray
    spectra: np.ndarray | SampledSpectra


@dataclass(frozen=True)
class BandImage:
    """A noisy image of one band (Eq. 10.1): ``values`` ``(height, width)`` of image
    ``image`` in band index ``band``, matched to the reconstruction after a Gaussian filter of
    standard deviation ``sigma_px`` pixels (0 matches pixel by pixel), each pixel's match
    weighted by ``weight`` ``(height, width)`` in [0, 1] (``None``: 1 everywhere, as the
    thesis; a pixel of weight 0 gives no data)."""

    image: int
    band: int
    values: np.ndarray
    sigma_px: float
    weight: np.ndarray | None = None


@dataclass(frozen=True)
class DeviceIntegrals:
    """General device readings (Eq. 6.9): ``weights`` ``(m, n_pixels * K)`` (sparse, over the
    row-major flattened cube), ``values`` ``(m,)`` and optional per-reading ``alpha`` factors
    :math:`\\alpha_j / \\alpha` (default 1). A reading fixes one value, so it anchors one
    graph component (its first pixel's) against the metameric blacks; the other components it
    reaches are linked like those without data
    (:func:`recon.spectralize.appearance.connect_components`)."""

    weights: sparse.spmatrix
    values: np.ndarray
    alpha: np.ndarray | None = None


@dataclass(frozen=True)
class EnergyWeights:
    """Primed weights :math:`\\alpha', \\beta', \\gamma', \\delta'` of Eq. 6.11 / 10.13.

    ``delta=None`` follows the thesis: :math:`\\delta' = 0.1` for the noisy band-image energy
    of Eq. 10.12 (band images present), no smoothness term (Eq. 6.9/6.10) otherwise. With
    sparse point spectra a smoothness term competes with the prior at every pixel and stops
    the spectra measured at a few pixels from spreading along the neighbour graph.
    """

    alpha: float = 1.0
    beta: float = 1.0
    gamma: float = 1.0
    delta: float | None = None

    def smoothness(self, has_band_images: bool) -> float:
        """:math:`\\delta'` in effect for an energy with or without band images."""
        if self.delta is not None:
            return float(self.delta)
        return 0.1 if has_band_images else 0.0

    def __post_init__(self) -> None:
        for name in ("alpha", "beta", "gamma", "delta"):
            value = getattr(self, name)
            if value is None:
                continue
            if not (np.isfinite(value) and value >= 0):
                raise InputError(f"weights.{name}: expected a finite value >= 0, got {value}")
        if self.alpha == 0:
            raise InputError("weights.alpha: expected > 0; without data nothing is known")


@dataclass
class SpectralizationProblem:
    """An assembled energy: its terms, absolute weights, scale factors :math:`f_i` and graph."""

    terms: list[Any]
    weights: list[float]
    scale: np.ndarray  # f_i, (n_pixels,)
    image_shape: tuple[int, int, int]  # (n_images, height, width)
    n_bands: int
    graph_links: int
    graph_added: int
    timings_s: dict[str, float] = field(default_factory=dict)
    base: np.ndarray | None = None  # (n_pixels, K): f-scaled B of prior="regression", or None

    @property
    def n_pixels(self) -> int:
        return int(self.scale.size)

    def energy(self, scaled: np.ndarray, coefficients: np.ndarray | None = None) -> float:
        """:math:`E` at the scaled image :math:`X = f S`, ``(n_pixels, K)``. Where
        :math:`X = Y P^T` with orthonormal :math:`P` (``(K, r)``, as the Kronecker solver's
        directions), ``coefficients`` :math:`Y` give the prior term in ``r`` columns instead of
        ``K``: :math:`\\mathrm{tr}(X^T L X) = \\mathrm{tr}(Y^T L Y)`."""
        energy = 0.0
        for term, weight in zip(self.terms, self.weights, strict=True):
            if isinstance(term, AppearancePriorTerm):
                energy += weight * term.sum_of_squares(
                    scaled if coefficients is None else coefficients
                )
                continue
            residual = np.ravel(term.apply(scaled))
            if not isinstance(term, _PRIOR_TERMS):  # the priors' targets are zero
                residual = residual - np.ravel(term.target)
            energy += weight * float(residual @ residual)
        return energy

    def operator(self) -> tuple[linalg.LinearOperator, np.ndarray]:
        """:math:`M_E` and :math:`b_E` of Eq. 6.12 (each term's rows scaled by
        :math:`\\sqrt{w}`), acting on the row-major flattened scaled image."""
        shape = (self.n_pixels, self.n_bands)
        roots = [np.sqrt(w) for w in self.weights]
        sizes = [t.n_rows for t in self.terms]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        rows = int(offsets[-1])
        # each term's rows, root weight and residual shape, found once (the priors' targets are
        # zero arrays as large as their residuals, built anew on every access)
        blocks = [
            (t, r, slice(start, stop), np.shape(t.target))
            for t, r, start, stop in zip(self.terms, roots, offsets[:-1], offsets[1:], strict=True)
        ]

        def matvec(vector: np.ndarray) -> np.ndarray:
            x = vector.reshape(shape)
            stacked = np.empty(rows)
            for t, r, span, _ in blocks:  # scaled straight into place, no copy to concatenate
                np.multiply(t.apply(x).ravel(), r, out=stacked[span])
            return stacked

        def rmatvec(vector: np.ndarray) -> np.ndarray:
            out = np.zeros(shape)
            for t, r, span, residual_shape in blocks:
                t.adjoint(r * vector[span].reshape(residual_shape), out)
            return out.ravel()

        operator = linalg.LinearOperator(
            (rows, shape[0] * shape[1]), matvec=matvec, rmatvec=rmatvec, dtype=np.float64
        )
        rhs = np.concatenate(
            [r * np.ravel(t.target) for t, r in zip(self.terms, roots, strict=True)]
        )
        return operator, rhs

    def kronecker_parts(self) -> tuple[sparse.csr_matrix, np.ndarray, FactoredRhs] | None:
        """:math:`A, B, C` of :mod:`recon.spectralize.kronecker` (:math:`C` in factors), or
        ``None`` where the energy has terms that break the split (band images, device
        integrals)."""
        n, bands = self.n_pixels, self.n_bands
        diagonal, spectral = np.zeros(n), np.zeros((bands, bands))
        laplacians, cameras, points = [], [], []
        for term, weight in zip(self.terms, self.weights, strict=True):
            if isinstance(term, PointSpectraTerm):
                diagonal += weight * np.bincount(term.pixels, minlength=n)
                points.append(_rows_matrix(term.pixels, weight * term.target, n))
            elif isinstance(term, CameraTerm):
                spectral += weight * term.response @ term.response.T
                cameras.append((term.target, weight * term.response.T))
            elif isinstance(term, AppearancePriorTerm):
                laplacians.append(weight * term.laplacian)
            elif isinstance(term, SpectralSmoothnessTerm):
                differences = term.difference_matrix()
                spectral += weight * differences @ differences.T
            else:
                return None
        rhs = FactoredRhs(
            np.hstack([target for target, _ in cameras]),
            np.vstack([right for _, right in cameras]),
            sum(points, sparse.csr_matrix((n, bands))),
        )
        spatial = sum(laplacians, sparse.diags(diagonal, format="csr"))
        return spatial.tocsr(), spectral, rhs


def _rows_matrix(pixels: np.ndarray, values: np.ndarray, n_pixels: int) -> sparse.csr_matrix:
    """``(n_pixels, K)`` sparse matrix with ``values`` added at the rows ``pixels``."""
    bands = values.shape[1]
    return sparse.csr_matrix(
        (values.ravel(), (np.repeat(pixels, bands), np.tile(np.arange(bands), pixels.size))),
        shape=(n_pixels, bands),
    )


@dataclass(frozen=True)
class SpectralizationResult:
    """Reconstructed spectra (leading shape of the RGB input, then ``K``) and solver facts."""

    spectra: np.ndarray
    solver: str
    iterations: int
    energy: float
    converged: bool
    graph_links: int
    graph_added: int
    timings_s: dict[str, float]


def _as_images(rgb: np.ndarray) -> np.ndarray:
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim == 3:
        rgb = rgb[None]
    if rgb.ndim != 4 or min(rgb.shape) < 1:
        raise InputError(
            f"rgb: expected (height, width, channels) or (n_images, height, width, channels), "
            f"got shape {rgb.shape}"
        )
    if not np.all(np.isfinite(rgb)):
        raise InputError("rgb: camera values must be finite (found NaN or inf)")
    return rgb


def _grid_and_values(
    spectra: np.ndarray | SampledSpectra, grid: WavelengthGrid | None, what: str
) -> tuple[np.ndarray, WavelengthGrid | None]:
    """Unwrap ``SampledSpectra``; refuse spectra on a grid other than ``grid``."""
    if not isinstance(spectra, SampledSpectra):
        return np.asarray(spectra, dtype=np.float64), grid
    if grid is not None and spectra.grid != grid:
        raise InputError(
            f"{what}: sampled on {spectra.grid.describe()} but the response is on "
            f"{grid.describe()}; resample one of them with recon.spectra.resample"
        )
    return spectra.values, spectra.grid


def _checked_response(response: np.ndarray, channels: int) -> np.ndarray:
    response = np.asarray(response, dtype=np.float64)
    if response.ndim != 2 or response.shape[1] != channels or response.shape[0] < 2:
        raise InputError(
            f"response: expected (K bands, {channels} channels) to match the rgb channels, got "
            f"shape {response.shape}"
        )
    if not np.all(np.isfinite(response)):
        raise InputError("response: values must be finite (found NaN or inf)")
    return response


def dynamic_scale(images: np.ndarray, p_dyn: float) -> np.ndarray:
    """:math:`f_i = (\\sum_c V_i^c)^{-p_{dyn}}` (Eq. 10.2). Sums below :data:`DYNAMIC_FLOOR`
    times the mean sum (holder, shadows, noise: dark pixels whose sum noise can make negative)
    are raised to that floor."""
    if not 0 <= p_dyn <= 1:
        raise InputError(f"p_dyn: expected a value in [0, 1], got {p_dyn}")
    brightness = images.sum(axis=-1).ravel()
    if p_dyn == 0:
        return np.ones_like(brightness)
    mean = float(np.mean(brightness))
    if mean <= 0:
        raise InputError(
            "rgb: dynamic-range compression (p_dyn > 0) needs a positive mean pixel sum"
        )
    return np.maximum(brightness, DYNAMIC_FLOOR * mean) ** -p_dyn


def _point_term(
    data: PointSpectra, scale: np.ndarray, bands: int, grid: WavelengthGrid | None
) -> PointSpectraTerm:
    pixels = np.asarray(data.pixels)
    spectra, _ = _grid_and_values(data.spectra, grid, "point_spectra.spectra")
    if pixels.ndim != 1 or not np.issubdtype(pixels.dtype, np.integer):
        raise InputError(f"point_spectra.pixels: expected 1-D integers, got {pixels.dtype}")
    if spectra.shape != (pixels.size, bands):
        raise InputError(
            f"point_spectra.spectra: expected shape ({pixels.size}, {bands}) = (pixels, bands of "
            f"the response), got {spectra.shape}"
        )
    if pixels.size and (pixels.min() < 0 or pixels.max() >= scale.size):
        raise InputError(
            f"point_spectra.pixels: expected indices in [0, {scale.size}), got "
            f"[{pixels.min()}, {pixels.max()}]"
        )
    if not np.all(np.isfinite(spectra)):
        raise InputError("point_spectra.spectra: values must be finite (found NaN or inf)")
    return PointSpectraTerm(pixels.astype(np.intp), spectra * scale[pixels, None])


def _band_term(
    data: BandImage, scale: np.ndarray, image_shape: tuple[int, int, int], bands: int
) -> FilteredBandTerm:
    count, height, width = image_shape
    values = np.asarray(data.values, dtype=np.float64)
    if values.shape != (height, width):
        raise InputError(
            f"band_images: image {data.image} band {data.band} has shape {values.shape}, "
            f"expected ({height}, {width}) like the rgb images"
        )
    if not (0 <= data.image < count and 0 <= data.band < bands):
        raise InputError(
            f"band_images: image {data.image} / band {data.band} out of range ({count} images, "
            f"{bands} bands)"
        )
    if not (np.isfinite(data.sigma_px) and data.sigma_px >= 0):
        raise InputError(f"band_images: sigma_px must be >= 0, got {data.sigma_px}")
    if not np.all(np.isfinite(values)):
        raise InputError(f"band_images: image {data.image} band {data.band} has NaN or inf values")
    weight = None if data.weight is None else np.asarray(data.weight, dtype=np.float64)
    if weight is not None and (
        weight.shape != (height, width) or not np.all((weight >= 0) & (weight <= 1))
    ):
        raise InputError(
            f"band_images: image {data.image} band {data.band}: expected a weight of shape "
            f"({height}, {width}) in [0, 1], got shape {weight.shape}"
        )
    size = height * width
    plane = scale[data.image * size : (data.image + 1) * size].reshape(height, width) * values
    target = gaussian_plane(plane if weight is None else weight * plane, float(data.sigma_px))
    return FilteredBandTerm(
        data.image, data.band, float(data.sigma_px), (height, width), target, weight
    )


def _device_term(data: DeviceIntegrals, scale: np.ndarray, bands: int) -> DeviceIntegralTerm:
    weights = sparse.csr_matrix(data.weights, dtype=np.float64)
    values = np.asarray(data.values, dtype=np.float64)
    columns = scale.size * bands
    if weights.shape != (values.size, columns):
        raise InputError(
            f"device_integrals.weights: expected shape ({values.size}, {columns}) = (readings, "
            f"pixels x bands), got {weights.shape}"
        )
    alpha = np.ones(values.size) if data.alpha is None else np.asarray(data.alpha, np.float64)
    if alpha.shape != values.shape or np.any(alpha < 0) or not np.all(np.isfinite(values)):
        raise InputError(
            "device_integrals: values must be finite and alpha non-negative, one per reading"
        )
    # Scaled unknowns X = f S: column (i, l) of the weights is divided by f_i.
    weights = weights @ sparse.diags(np.repeat(1.0 / scale, bands))
    root = np.sqrt(alpha)
    return DeviceIntegralTerm(sparse.diags(root) @ weights, root * values)


def _regression_matrix(
    scaled_rgb: np.ndarray,
    data_terms: list[Any],
    response: np.ndarray,
    neutral: np.ndarray | None,
) -> np.ndarray:
    """:math:`W` ``(C, K)``: the least-squares map from the known pixels' camera values to their
    spectra (both f-scaled), :math:`\\min_W \\lVert V_P W - D \\rVert^2`, the inverse matrix of
    Hardeberg (thesis Sec. 6.1); with a ``neutral`` spectrum :math:`n`, subject to
    :math:`(n R_{cam}) W = n` (:func:`build_problem`)."""
    points = [t for t in data_terms if isinstance(t, PointSpectraTerm)]
    if not points:
        raise InputError(
            "prior: 'regression' learns its map from point spectra; pass known_pixels and "
            "known_spectra, or use prior='spectra'"
        )
    pixels = np.concatenate([t.pixels for t in points])
    spectra = np.concatenate([t.target for t in points])
    if neutral is None:
        return np.linalg.lstsq(scaled_rgb[pixels], spectra, rcond=None)[0]
    seen = neutral @ response  # (C,): the neutral's camera values
    norm = float(np.linalg.norm(seen))
    if norm == 0:
        raise InputError("neutral: its camera values are zero; expected a spectrum the camera sees")
    complement = np.linalg.svd(seen[None, :])[2][1:]  # (C - 1, C): orthogonal to seen
    fixed = np.outer(seen / norm, neutral / norm)  # seen to neutral, its complement to zero
    free = np.linalg.lstsq(
        scaled_rgb[pixels] @ complement.T, spectra - scaled_rgb[pixels] @ fixed, rcond=None
    )[0]
    return fixed + complement.T @ free


def neighbour_graph(
    rgb: np.ndarray,
    *,
    appearance: str = "rgb",
    appearance_options: dict[str, Any] | None = None,
    neighbours: int = 3,
    p_dyn: float = 0.0,
) -> NeighbourGraph:
    """The appearance links :math:`N_i` of Eq. 6.3 that :func:`build_problem` finds for these
    camera values and options, before components without data are linked: found once, they
    serve every solve over the same image (``graph=``), whatever spectra are known.

    Parameters
    ----------
    rgb
        ``(H, W, C)`` or ``(N, H, W, C)`` camera values.
    appearance, appearance_options, neighbours, p_dyn
        As in :func:`build_problem`.

    Returns
    -------
    NeighbourGraph
    """
    images = _as_images(rgb)
    scale = dynamic_scale(images, p_dyn)
    scaled = images * scale.reshape(*images.shape[:3], 1)
    points = appearance_points(scaled, appearance, **(appearance_options or {}))
    return appearance_neighbours(points, k=neighbours)


def graph_for(rgb: np.ndarray, options: Mapping[str, Any]) -> NeighbourGraph:
    """:func:`neighbour_graph` of ``rgb`` with the options among ``options`` (energy and solver
    options of :func:`reconstruct`) that shape the graph: ``appearance``,
    ``appearance_options``, ``neighbours`` and ``p_dyn``."""
    names = ("appearance", "appearance_options", "neighbours", "p_dyn")
    return neighbour_graph(rgb, **{key: options[key] for key in names if key in options})


def build_problem(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    point_spectra: PointSpectra | None = None,
    band_images: Sequence[BandImage] = (),
    device_integrals: DeviceIntegrals | None = None,
    weights: EnergyWeights = EnergyWeights(),
    appearance: str = "rgb",
    appearance_options: dict[str, Any] | None = None,
    neighbours: int = 3,
    p_dyn: float = 0.0,
    prior: str = "spectra",
    neutral: np.ndarray | None = None,
    regression: np.ndarray | None = None,
    graph: NeighbourGraph | None = None,
) -> SpectralizationProblem:
    """Assemble the energy of the module docstring.

    Parameters
    ----------
    rgb, response
        As in :func:`spectralize`.
    point_spectra, band_images, device_integrals
        The spectral data (at least one): see :class:`PointSpectra`, :class:`BandImage`,
        :class:`DeviceIntegrals`. Pixel indices run over ``(n_images, height, width)``.
    weights
        Primed weights (Eq. 6.11 / 10.13); see :class:`EnergyWeights` for the default
        :math:`\\delta'`.
    appearance, appearance_options
        Appearance space ``"rgb"``, ``"rgbxy"`` or ``"patch"`` and its options
        (:func:`recon.spectralize.appearance.appearance_points`).
    neighbours
        :math:`|N_i|`, default 3 (section 6.2).
    p_dyn
        Dynamic-range compression exponent of Eq. 10.2 (0: none; the thesis used 0.5-0.6 for
        BTFs).
    prior
        What the appearance prior (Eq. 6.3) and the smoothness term hold alike between
        neighbours: ``"spectra"``, the spectra themselves (the thesis); or ``"regression"``, the
        spectra minus :math:`B_i = V_i W`, where :math:`W` maps camera values to spectra by least
        squares over the point spectra (Hardeberg's inverse matrix, Sec. 6.1). With
        ``"regression"`` neighbours that differ in brightness or colour differ in spectrum as
        the known spectra say they should (shading, smooth colour gradients); but the noise of
        :math:`V_i` reaches the spectra through :math:`W`. :func:`recon.spectralize.choose_prior`
        picks one from held-out known spectra.
    neutral
        With ``prior="regression"``, ``(K,)`` a spectrum that :math:`W` must map its own camera
        values to exactly: the interface reflection of the dichromatic reflection model, which
        for dielectrics is neutral, a flat reflectance factor (Shafer 1985; Lee et al. 1990).
        A texel under a highlight is then its body colour plus that spectrum in the base too,
        where a :math:`W` fitted to spots of body colours alone extrapolates to the highlight's
        camera values freely (on the twin's lego, all spots at one pair, the mirror pair came
        out at 98 % with it free, 15 % with the flat spectrum fixed). None: :math:`W` free.
    regression
        :math:`W` ``(C, K)`` of ``prior="regression"`` given by the caller (e.g. made from an
        area reading, :mod:`recon.btf.reading_spectralization`); None fits it to the point
        spectra.
    graph
        The appearance links of these pixels found before by :func:`neighbour_graph` with the
        same ``appearance``, ``appearance_options``, ``neighbours`` and ``p_dyn`` (e.g. once
        for all the solves of a cross-validation); None finds them. Components without data are
        linked here either way.

    Returns
    -------
    SpectralizationProblem
    """
    if prior not in PRIORS:
        raise InputError(f"prior: expected one of {PRIORS}, got {prior!r}")
    if regression is not None and prior != "regression":
        raise InputError(f"regression: a map for prior='regression', given with prior={prior!r}")
    images = _as_images(rgb)
    response_values, grid = _grid_and_values(response, None, "response")
    if isinstance(response, SampledSpectra):
        response_values = response_values.T  # (channels, K) rows -> (K, channels)
    response = _checked_response(response_values, images.shape[-1])
    bands, channels = response.shape
    if neutral is not None and prior != "regression":
        raise InputError(f"neutral: a spectrum for prior='regression', given with prior={prior!r}")
    image_shape = images.shape[:3]
    scale = dynamic_scale(images, p_dyn)
    scaled_rgb = images.reshape(-1, channels) * scale[:, None]

    data_terms: list[Any] = []
    if point_spectra is not None:
        data_terms.append(_point_term(point_spectra, scale, bands, grid))
    data_terms += [_band_term(b, scale, image_shape, bands) for b in band_images]
    if device_integrals is not None:
        data_terms.append(_device_term(device_integrals, scale, bands))
    data_rows = sum(t.n_rows for t in data_terms)
    if data_rows == 0:
        raise InputError(
            "spectralize: no spectral data given; pass point_spectra, band_images or "
            "device_integrals (an RGB image alone leaves the spectra undetermined)"
        )
    has_data = np.zeros(scale.size, dtype=bool)
    for term in data_terms:
        if isinstance(term, PointSpectraTerm):
            has_data[term.pixels] = True
        elif isinstance(term, FilteredBandTerm):
            has_data[term.pixel_slice()] |= True if term.weight is None else term.weight.ravel() > 0
        else:  # a reading anchors one value per band: the component of its first pixel
            readings = term.weights.tocsr()
            reached = np.diff(readings.indptr) > 0
            has_data[readings.indices[readings.indptr[:-1][reached]] // bands] = True

    started = time.perf_counter()
    points = appearance_points(
        scaled_rgb.reshape(*image_shape, channels), appearance, **(appearance_options or {})
    )
    if graph is None:
        graph = appearance_neighbours(points, k=neighbours)
    elif graph.n_pixels != scale.size:
        raise InputError(
            f"graph: links of {graph.n_pixels} pixels for an image of {scale.size}; expected the "
            "appearance links of these pixels"
        )
    graph_s = time.perf_counter() - started
    graph = connect_components(graph, points, has_data)
    connect_s = time.perf_counter() - started - graph_s

    n = scale.size
    prior_rows = bands * graph.n_links
    delta = weights.smoothness(has_band_images=bool(band_images))
    smooth_rows = n * (bands - 1) if delta > 0 else 0
    total = data_rows + channels * n + prior_rows + smooth_rows  # Eq. 6.11 / 10.13 numerator
    data_mean = np.mean(np.concatenate([np.abs(np.ravel(t.target)) for t in data_terms]))
    rgb_mean = float(np.mean(np.abs(scaled_rgb)))
    if rgb_mean == 0 or data_mean == 0:
        raise InputError("spectralize: rgb and spectral data must not be all zero")
    terms = [*data_terms, CameraTerm(response, scaled_rgb)]
    absolute = [weights.alpha * total / data_rows] * len(data_terms)
    absolute.append(weights.beta * (data_mean / rgb_mean) * total / (channels * n))
    if graph.n_links:
        terms.append(AppearancePriorTerm(graph, bands))
        absolute.append(weights.gamma * total / prior_rows)
    if smooth_rows:
        terms.append(SpectralSmoothnessTerm(n, bands))
        absolute.append(delta * total / smooth_rows)
    problem = SpectralizationProblem(
        terms,
        absolute,
        scale,
        image_shape,
        bands,
        graph.n_links,
        graph.added,
        {"neighbours": graph_s, "connect": connect_s},
    )
    if prior == "regression":
        return regression_prior(problem, neutral=neutral, regression=regression)
    return problem


def regression_prior(
    problem: SpectralizationProblem,
    *,
    neutral: np.ndarray | None = None,
    regression: np.ndarray | None = None,
) -> SpectralizationProblem:
    """The energy of ``problem`` (built with ``prior="spectra"``) with the regression prior
    instead: the prior and smoothness terms act on :math:`X - B`, so the other terms' targets
    lose :math:`B`'s share. Its terms, weights and graph are those of ``problem``, so one
    assembly serves both priors (:func:`recon.spectralize.reconstruct_priors`).

    Parameters
    ----------
    problem
        A problem of :func:`build_problem` with ``prior="spectra"``.
    neutral, regression
        As in :func:`build_problem`.

    Returns
    -------
    SpectralizationProblem
        ``problem`` as :func:`build_problem` assembles it with ``prior="regression"``.
    """
    if problem.base is not None:
        raise InputError("problem: expected one built with prior='spectra'")
    camera = next(t for t in problem.terms if isinstance(t, CameraTerm))
    scaled_rgb, response = camera.target, camera.response
    bands, channels = response.shape
    if neutral is not None:
        neutral = np.asarray(neutral, dtype=np.float64)
        if neutral.shape != (bands,):
            raise InputError(
                f"neutral: expected shape ({bands},) with prior='regression', got shape "
                f"{neutral.shape}"
            )
    if regression is None:
        data_terms = [t for t in problem.terms if not isinstance(t, (CameraTerm, *_PRIOR_TERMS))]
        regression = _regression_matrix(scaled_rgb, data_terms, response, neutral)
    elif np.shape(regression) != (channels, bands) or not np.all(np.isfinite(regression)):
        raise InputError(
            f"regression: expected a finite ({channels}, {bands}) map from camera values to "
            f"spectra, got shape {np.shape(regression)}"
        )
    base = scaled_rgb @ regression
    terms = [
        t if isinstance(t, _PRIOR_TERMS) else replace(t, target=t.target - t.apply(base))
        for t in problem.terms
    ]
    return replace(problem, terms=terms, base=base)


def _band_regression_start(problem: SpectralizationProblem) -> np.ndarray | None:
    """A starting point for the iterative solvers of an energy with band images (Eq. 10.1):
    per band, the least-squares map from the filtered camera values of the images a band was
    taken of to the band's filtered values (:math:`\\min_w \\lVert F * (V w) - F * (f D^b)
    \\rVert^2`, Hardeberg's inverse matrix, thesis Sec. 6.1, fitted on the band images instead
    of point spectra), applied to every pixel's camera values; relative to :math:`B` for
    ``prior="regression"``. ``None`` without band images.

    It is the same energy's solution that is then sought, from nearer: on the dome processing
    test's capture LSMR took 161 and 145 iterations instead of 190 and 204 (colour checker and
    Lego bricks; BENCHMARKS.md, "Dome processing")."""
    bands = [t for t in problem.terms if isinstance(t, FilteredBandTerm)]
    if not bands:
        return None
    camera = next(t for t in problem.terms if isinstance(t, CameraTerm))
    scaled_rgb = camera.target
    # (image, sigma, the weight's identity): (pixels, C); the bands of one image share a weight
    filtered: dict[tuple[int, float, int], np.ndarray] = {}
    systems: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
    for term in bands:
        key = (term.image, term.sigma_px, id(term.weight))
        if key not in filtered:
            planes = scaled_rgb[term.pixel_slice()].T.reshape(-1, *term.shape)
            if term.weight is not None:
                planes = planes * term.weight
            filtered[key] = np.stack(
                [gaussian_plane(plane, term.sigma_px).ravel() for plane in planes], axis=1
            )
        systems.setdefault(term.band, []).append((filtered[key], term.target.ravel()))
    regression = np.zeros((scaled_rgb.shape[1], problem.n_bands))
    for band, pairs in systems.items():
        values = np.concatenate([seen for seen, _ in pairs])
        targets = np.concatenate([target for _, target in pairs])
        regression[:, band] = np.linalg.lstsq(values, targets, rcond=None)[0]
    start = scaled_rgb @ regression
    return start if problem.base is None else start - problem.base


def _solve_least_squares(
    problem: SpectralizationProblem,
    method: str,
    max_iterations: int,
    tol: float,
    initial: np.ndarray | None,
    progress: bool,
) -> tuple[np.ndarray, int, bool]:
    operator, rhs = problem.operator()
    with (
        threadpool_limits(1, user_api="blas"),
        progress_steps(f"spectralize: {method}", max_iterations, enabled=progress) as advance,
    ):
        counted = linalg.LinearOperator(
            operator.shape,
            matvec=lambda v: (advance(), operator.matvec(v))[1],
            rmatvec=operator.rmatvec,
            dtype=np.float64,
        )
        x0 = None if initial is None else initial.ravel()
        if method == "lsqr":
            out = linalg.lsqr(counted, rhs, atol=tol, btol=tol, iter_lim=max_iterations, x0=x0)
        else:
            out = linalg.lsmr(counted, rhs, atol=tol, btol=tol, maxiter=max_iterations, x0=x0)
    iterations, status = int(out[2]), int(out[1])
    return out[0].reshape(problem.n_pixels, problem.n_bands), iterations, status in (1, 2, 4, 5)


def reconstruct(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    solver: str = "auto",
    tol: float = 1e-6,
    max_iterations: int = 500,
    initial: np.ndarray | None = None,
    progress: bool = False,
    **energy: Any,
) -> SpectralizationResult:
    """Reconstruct spectral images and report how (thesis chapters 6, 10); see
    :func:`spectralize` for the plain entry point.

    Parameters
    ----------
    rgb
        ``(height, width, C)`` or, for a joint reconstruction of several images (BTF slices),
        ``(n_images, height, width, C)`` linear camera values :math:`V`.
    response
        :math:`R_{cam}`, ``(K, C)``: camera sensitivity times light per band, so that
        :math:`V_i \\approx S_i R_{cam}`; or ``SampledSpectra`` with one row per channel, whose
        grid the point spectra must share.
    **energy
        The energy: ``point_spectra``, ``band_images``, ``device_integrals``, ``weights``,
        ``appearance``, ``appearance_options``, ``neighbours``, ``p_dyn``, ``prior``,
        ``regression``; see :func:`build_problem`.
    solver
        ``"auto"``, ``"multigrid"``, ``"lsqr"`` or ``"lsmr"``.
    tol
        Stopping tolerance: relative residual per column (multigrid) or LSQR/LSMR's
        ``atol = btol``.
    max_iterations
        Iteration cap (per column for multigrid).
    initial
        Optional starting spectra (same shape as the result), e.g. the previous BTF slice.
    progress
        Show progress bars.

    Returns
    -------
    SpectralizationResult
        ``spectra`` with the leading shape of ``rgb`` and ``K`` bands, and solver facts.

    Examples
    --------
    >>> import numpy as np
    >>> response = np.random.default_rng(0).random((8, 3))
    >>> materials = np.random.default_rng(1).random((2, 8))
    >>> truth = materials[np.repeat([0, 1], 15)].reshape(6, 5, 8)  # two halves
    >>> known = PointSpectra(np.arange(30), truth.reshape(30, 8))
    >>> result = reconstruct(truth @ response, response, point_spectra=known, tol=1e-10)
    >>> bool(np.allclose(result.spectra, truth, atol=1e-5)), result.solver
    (True, 'multigrid')
    """
    if solver not in SOLVERS:
        raise InputError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    if not (tol > 0 and max_iterations >= 1):
        raise InputError(
            f"tol, max_iterations: expected tol > 0 and max_iterations >= 1, got {tol}, "
            f"{max_iterations}"
        )
    problem = build_problem(rgb, response, **energy)
    shape = (problem.n_pixels, problem.n_bands)
    scaled_initial = None
    if initial is not None:
        initial = np.asarray(initial, dtype=np.float64)
        if initial.size != shape[0] * shape[1] or not np.all(np.isfinite(initial)):
            raise InputError(
                f"initial: expected finite spectra with {shape[0]} x {shape[1]} values, got "
                f"shape {initial.shape}"
            )
        scaled_initial = initial.reshape(shape) * problem.scale[:, None]
        if problem.base is not None:
            scaled_initial = scaled_initial - problem.base
    started = time.perf_counter()
    parts = problem.kronecker_parts() if solver in ("auto", "multigrid") else None
    assembly_s = time.perf_counter() - started
    if solver == "multigrid" and parts is None:
        raise InputError(
            "solver='multigrid' needs an energy with point spectra, camera, prior and "
            "smoothness terms only; use 'lsqr' or 'lsmr' with band images or device integrals"
        )
    started = time.perf_counter()
    if parts is not None:
        scaled, info = solve_kronecker_sum(
            *parts,
            rtol=tol,
            max_iterations=max_iterations,
            initial=scaled_initial,
            progress=progress,
        )
        used, iterations, converged = "multigrid", int(info.iterations.max()), info.converged
        coefficients = info.coefficients
    else:
        coefficients = None
        used = "lsmr" if solver == "auto" else solver
        if scaled_initial is None:
            scaled_initial = _band_regression_start(problem)
        scaled, iterations, converged = _solve_least_squares(
            problem, used, max_iterations, tol, scaled_initial, progress
        )
    timings = {**problem.timings_s, "assembly": assembly_s, "solve": time.perf_counter() - started}
    energy_at_solution = problem.energy(scaled, coefficients)
    if problem.base is not None:
        scaled = scaled + problem.base
    spectra = scaled
    if np.any(problem.scale != 1.0):  # dynamic-range compression (Eq. 10.2) undone
        spectra = scaled / problem.scale[:, None]
    return SpectralizationResult(
        spectra=spectra.reshape(*np.shape(rgb)[:-1], problem.n_bands),
        solver=used,
        iterations=iterations,
        energy=energy_at_solution,
        converged=converged,
        graph_links=problem.graph_links,
        graph_added=problem.graph_added,
        timings_s=timings,
    )


def spectralize(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    known_pixels: np.ndarray | None = None,
    known_spectra: np.ndarray | SampledSpectra | None = None,
    band_images: Sequence[BandImage] | None = None,
    appearance: str = "rgb",
    k: int = 3,
    **options: Any,
) -> np.ndarray:
    """Spectral image from RGB plus known spectra and/or noisy band images (the project's
    stable entry point; thesis Eq. 6.10 and 10.12).

    Parameters
    ----------
    rgb
        ``(H, W, C)`` or ``(N, H, W, C)`` camera values.
    response
        ``(K, C)`` :math:`R_{cam}` on the cube's grid.
    known_pixels, known_spectra
        Flat indices into the ``(N,) H, W`` pixels and their ``(n, K)`` spectra (Eq. 6.10).
    band_images
        Noisy band images for Eq. 10.1/10.12 (:class:`BandImage`).
    appearance, k
        Appearance space (Eq. 6.4-6.6) and neighbours per pixel (section 6.2).
    **options
        Passed on to :func:`reconstruct` (``solver``, ``tol``, ``weights``, ``p_dyn``, ``prior``,
        ``device_integrals``, ``appearance_options``, ``initial``, ``progress``, ...).

    Returns
    -------
    numpy.ndarray
        The cube: the leading shape of ``rgb``, then ``K`` bands.

    Examples
    --------
    >>> import numpy as np
    >>> response = np.random.default_rng(0).random((8, 3))
    >>> materials = np.random.default_rng(1).random((2, 8))
    >>> truth = materials[np.repeat([0, 1], 15)].reshape(6, 5, 8)
    >>> cube = spectralize(truth @ response, response, known_pixels=np.arange(30),
    ...                    known_spectra=truth.reshape(30, 8), tol=1e-10)
    >>> bool(np.allclose(cube, truth, atol=1e-5))
    True
    """
    if (known_pixels is None) != (known_spectra is None):
        raise InputError(
            "known_pixels, known_spectra: give both (indices and their spectra) or neither"
        )
    point_spectra = None
    if known_pixels is not None and known_spectra is not None:
        point_spectra = PointSpectra(np.asarray(known_pixels), known_spectra)
    return reconstruct(
        rgb,
        response,
        point_spectra=point_spectra,
        band_images=() if band_images is None else band_images,
        appearance=appearance,
        neighbours=k,
        **options,
    ).spectra
