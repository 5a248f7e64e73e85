"""Spectral characterization of RGB cameras from colour-chart photographs (thesis chapter 9).

A camera's effective spectral response :math:`R^{eff}` (K x 3) maps the light reflected by a chart
field to its device RGB: :math:`D_{j,c} = \\sum_i S_{i,j} L_i R_{i,c}` (Eq. 9.4). Given the
photographed field means :math:`D`, the known field reflectances :math:`S` and the illuminant
:math:`L`, ``estimate_response`` recovers :math:`R^{eff}`:

- ``method="basic"``: Eq. 9.3-9.5, one linear least-squares problem per channel.
- ``method="extended"``: Eq. 9.6-9.11: per-field shading factors :math:`F_j` smooth over
  neighbouring fields (9.9), per-field specularity :math:`\\sigma_j` added to the reflectance
  (9.7), smoothness reweighted by the previous estimate (9.8), damping to the previous estimate
  (9.10) and a border term (9.11); alternating least squares (:math:`R, F` then :math:`\\sigma`),
  multigrid over the spectral resolution from 8 components, +4 per level, and field weights
  (Eq. 9.12-9.14). Several photographs (different illuminants) can be combined.
- ``method="extended"`` with a prior (the default): Eq. 9.6 plus a term
  :math:`\\lambda E_{prior}` that keeps each channel's shape near those of measured cameras
  (``recon.camera_prior``): the energy of a Gaussian over peak-normalized responses, free in
  scale, divided by the square of the previous estimate's peak as Eq. 9.8 divides by the
  previous estimate. The solve starts at full spectral resolution: the prior, not the coarse
  multigrid levels, keeps the first estimates plausible. By default the prior is learned from
  the 51 measured cameras shipped with spectwin (:func:`measured_response_prior`); ``prior=None``
  is the thesis's method.

Also: the reference method with the LCTF as monochromator (Eq. 9.15-9.16), the illuminant from a
colour temperature (9.5.5), the prediction error for cross-validation (Eq. 9.17) and the
RGB-to-XYZ profile matrix for a new illuminant (Eq. 9.18).

Conventions (thesis 9.4.2): device RGB and light spectra are normalized to a mean of one and
reflectances lie in [0, 1]; the returned response is in the units of the inputs. With shading
factors free, the overall scale of :math:`R^{eff}` is that of the mean shading (fixed to 1).

References
----------
- The thesis, chapter 9, Eq. 9.3-9.18.
- Hubel, P. M., Sherman, D., & Farrell, J. E. (1994). A comparison of methods of sensor spectral
  sensitivity estimation. IS&T/SID Color Imaging Conference (the pseudo-inverse reference).
- Jiang, J., Liu, D., Gu, J., & Süsstrunk, S. (2013). What is the space of spectral sensitivity
  functions for digital color cameras? WACV, 168-179 (camera responses span a small space; the
  prior of ``recon.camera_prior``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal, overload

import colour
import numpy as np
from scipy import linalg, ndimage, optimize, spatial
from threadpoolctl import threadpool_limits

from recon.camera_prior import PRIOR_WEIGHT, ResponsePrior, learn_response_prior
from recon.errors import InputError
from recon.measured_data import camera_names, read_camera_sensitivities
from recon.spectra import WavelengthGrid, resample

__all__ = [
    "CharacterizationResult",
    "estimate_response",
    "field_weights",
    "fit_residuals",
    "illuminant_from_temperature",
    "measured_response_prior",
    "prediction_error",
    "profile_matrix",
    "reference_response",
]

_SMOOTHNESS_FLOOR = 0.05  # of the previous response's peak, in the denominators of Eq. 9.8

MeasuredPrior = Literal["measured"]
"""``prior="measured"``: the prior learned from all the measured cameras that ship with spectwin
(:func:`measured_response_prior`), on the estimate's wavelengths."""


@dataclass(frozen=True)
class CharacterizationResult:
    """Recovered response ``(K, 3)``, shading ``(P, J)`` and specularity ``(P, J)`` per photo."""

    response: np.ndarray
    shading: np.ndarray
    specularity: np.ndarray
    iterations: int


def _as_photos(
    chart_rgb: np.ndarray, reflectances: np.ndarray, illuminant: np.ndarray, wavelengths: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    wavelengths = np.asarray(wavelengths, np.float64)
    if wavelengths.ndim != 1 or wavelengths.size < 4 or np.any(np.diff(wavelengths) <= 0):
        raise InputError("wavelengths: expected at least 4 strictly increasing values in nm")
    reflectances = np.asarray(reflectances, np.float64)
    if reflectances.ndim != 2 or reflectances.shape[1] != wavelengths.size:
        raise InputError(
            f"reflectances: expected (fields, {wavelengths.size}), got {reflectances.shape}"
        )
    rgb = np.asarray(chart_rgb, np.float64)
    rgb = rgb[None] if rgb.ndim == 2 else rgb
    light = np.atleast_2d(np.asarray(illuminant, np.float64))
    if rgb.ndim != 3 or rgb.shape[1:] != (reflectances.shape[0], 3):
        raise InputError(
            f"chart_rgb: expected ({reflectances.shape[0]}, 3) or (photos, "
            f"{reflectances.shape[0]}, 3), got {np.shape(chart_rgb)}"
        )
    if light.shape != (rgb.shape[0], wavelengths.size):
        raise InputError(
            f"illuminant: expected ({wavelengths.size},) or ({rgb.shape[0]}, {wavelengths.size}), "
            f"got {np.shape(illuminant)}"
        )
    for name, values in (("chart_rgb", rgb), ("reflectances", reflectances), ("illuminant", light)):
        if not np.all(np.isfinite(values)):
            raise InputError(f"{name}: expected finite values, found NaN or infinity")
        if np.any(values < 0):
            raise InputError(f"{name}: expected non-negative values")
    if np.any(reflectances > 1):
        raise InputError("reflectances: expected diffuse reflectances in [0, 1]")
    return rgb, reflectances, light, wavelengths


def illuminant_from_temperature(temperature_k: float, wavelengths: np.ndarray) -> np.ndarray:
    """Relative spectrum of a black body at ``temperature_k`` (thesis 9.5.5), mean one."""
    if not temperature_k > 0:
        raise InputError(f"temperature_k: expected a positive temperature, got {temperature_k}")
    spectrum = colour.colorimetry.planck_law(
        np.asarray(wavelengths, np.float64) * 1e-9, temperature_k
    )
    return spectrum / spectrum.mean()


def measured_response_prior(wavelengths: np.ndarray) -> ResponsePrior:
    """The prior over responses learned from every measured camera shipped with spectwin.

    Parameters
    ----------
    wavelengths
        The estimate's ``K`` sample wavelengths in nm (strictly increasing). The cameras'
        sensitivities (``recon.measured_data.read_camera_sensitivities``, 380-780 nm in 5 nm
        steps) are averaged over each sample's cell, their end values held beyond 380-780 nm
        (where cameras respond little), as ``twin.studies.camchar_cameras`` tuned the prior.

    Returns
    -------
    ResponsePrior
        :func:`recon.camera_prior.learn_response_prior` of the 51 cameras, with its default
        components; the default ``prior`` of :func:`estimate_response` (the energy term added
        to Eq. 9.6). Learned once per grid.

    Examples
    --------
    >>> prior = measured_response_prior(np.arange(400.0, 701.0, 10.0))
    >>> prior.mean.shape, prior.cameras
    ((31, 3), 51)
    """
    grid = WavelengthGrid(np.asarray(wavelengths, np.float64))
    return _measured_prior(tuple(grid.wavelengths_nm.tolist()))


@lru_cache(maxsize=8)
def _measured_prior(wavelengths: tuple[float, ...]) -> ResponsePrior:
    grid = WavelengthGrid(np.array(wavelengths))
    responses = np.array(
        [
            resample(
                read_camera_sensitivities(name), grid, method="box", out_of_range="clamp"
            ).values.T
            for name in camera_names()
        ]
    )
    return learn_response_prior(responses, grid.wavelengths_nm)


def _interpolation_matrix(wavelengths: np.ndarray, count: int) -> np.ndarray:
    """(K, count) matrix interpolating ``count`` equally spaced samples linearly onto the grid."""
    coarse = np.linspace(wavelengths[0], wavelengths[-1], count)
    return np.column_stack([np.interp(wavelengths, coarse, np.eye(count)[m]) for m in range(count)])


def _smoothness_rows(count: int, previous: np.ndarray | None) -> np.ndarray:
    """Rows of (R_i - R_{i+1}) / (R'_i + R'_{i+1}) (Eq. 9.8; plain Eq. 9.5 without ``previous``)."""
    rows = np.zeros((count - 1, count))
    rows[np.arange(count - 1), np.arange(count - 1)] = 1.0
    rows[np.arange(count - 1), np.arange(1, count)] = -1.0
    if previous is not None:
        scale = previous[:-1] + previous[1:]
        rows /= (scale + _SMOOTHNESS_FLOOR * max(previous.max(), 1e-12))[:, None]
    return rows


def _basic(
    rgb: np.ndarray, reflectances: np.ndarray, light: np.ndarray, alpha: float
) -> np.ndarray:
    """Eq. 9.3-9.5: stacked photos, one regularized linear least-squares fit per channel."""
    design = np.concatenate([reflectances * photo_light for photo_light in light])
    smooth = np.sqrt(alpha) * _smoothness_rows(design.shape[1], None)
    system = np.vstack([design, smooth])
    response = np.empty((design.shape[1], 3))
    for channel in range(3):
        target = np.concatenate([rgb[:, :, channel].ravel(), np.zeros(smooth.shape[0])])
        response[:, channel] = optimize.lsq_linear(system, target, bounds=(0, np.inf)).x
    return response


def _distribution_weights(reflected: np.ndarray) -> np.ndarray:
    """:math:`w^{distrib}` (Eq. 9.13): weights in [0, 5] with mean one that minimize the variance
    across bands of the weighted sum of the reflected spectra ``(J, K)``."""
    count = reflected.shape[0]
    centred = reflected.T - reflected.T.mean(axis=0, keepdims=True)
    penalty = 1e3 * np.ones((1, count)) / count
    system = np.vstack([centred / np.abs(reflected).mean(), penalty])
    target = np.concatenate([np.zeros(centred.shape[0]), [1e3]])
    return optimize.lsq_linear(system, target, bounds=(0.0, 5.0)).x


def field_weights(
    reflectances: np.ndarray,
    light: np.ndarray,
    response: np.ndarray,
    distribution: np.ndarray | None = None,
) -> np.ndarray:
    """Field weights :math:`w_{j,c} = w_j^{distrib} + w_{j,c}^{slopes}` (Eq. 9.12-9.14), ``(J, 3)``.

    :math:`w^{distrib}` (Eq. 9.13) minimizes the variance across bands of the weighted sum of
    reflected spectra, with weights in [0, 5] and mean one. :math:`w^{slopes}` (Eq. 9.14) uses
    magnitudes of the finite-difference slopes (the thesis's signed products could cancel) and is
    normalized to mean one per channel, so that neither term dominates. ``distribution`` passes
    a precomputed :math:`w^{distrib}` (it depends on reflectances and light only).
    """
    reflected = reflectances * light  # (J, K)
    distrib = _distribution_weights(reflected) if distribution is None else distribution
    # A response is non-negative; an estimate can dip below zero at the ends, which would make
    # a field's weight negative (and its data rows imaginary in Eq. 9.6): its positive part.
    response = np.maximum(response, 0.0)
    slope_reflected = np.abs(np.gradient(reflected, axis=1))  # (J, K)
    slope_response = np.abs(np.gradient(response, axis=0))  # (K, 3)
    slopes = slope_reflected @ response + slope_reflected @ slope_response + reflected @ response
    slopes = slopes / np.maximum(slopes.mean(axis=0, keepdims=True), 1e-12)
    return distrib[:, None] + slopes


def _neighbour_laplacian(positions: np.ndarray) -> np.ndarray:
    """``(J, J)`` graph Laplacian of the fields whose distance is at most 1.5 x the smallest
    field distance: :math:`F^T \\Delta F = \\sum_{(j, n)} (F_j - F_n)^2` (Eq. 9.9)."""
    tree = spatial.cKDTree(positions)
    nearest = tree.query(positions, k=2)[0][:, 1].min()
    pairs = np.array(sorted(tree.query_pairs(1.5 * nearest)), dtype=int).reshape(-1, 2)
    adjacency = np.zeros((len(positions), len(positions)))
    adjacency[pairs[:, 0], pairs[:, 1]] = adjacency[pairs[:, 1], pairs[:, 0]] = 1.0
    return np.diag(adjacency.sum(axis=1)) - adjacency


def _prior_rows(
    prior_roots: np.ndarray, interpolate: np.ndarray, response_peaks: np.ndarray, weight: float
) -> np.ndarray:
    """Rows :math:`\\sqrt{\\lambda} L_c R_c / \\max R'_c` of the prior term per channel, on the
    coarse unknowns (``(3, K, count)``)."""
    return np.sqrt(weight) * (prior_roots @ interpolate) / response_peaks[:, None, None]


def _initial_peaks(
    rgb: np.ndarray, reflectances: np.ndarray, light: np.ndarray, prior: ResponsePrior
) -> np.ndarray:
    """Peaks of the multiple of the prior's mean that explains the mean device RGB (the scale
    of the prior term before there is a previous estimate)."""
    mean_reflected = (reflectances * light.mean(axis=0)).mean(axis=0)  # (K,)
    scale = rgb.mean(axis=(0, 1)) / (mean_reflected @ prior.mean)
    return scale * prior.mean.max(axis=0)


def _extended(
    rgb: np.ndarray,
    reflectances: np.ndarray,
    light: np.ndarray,
    wavelengths: np.ndarray,
    positions: np.ndarray,
    params: dict[str, float],
    max_iterations: int,
    tolerance: float,
    prior: ResponsePrior | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    photos, fields, _ = rgb.shape
    bands = wavelengths.size
    fixed = _FixedTerms(rgb, reflectances, light, _neighbour_laplacian(positions), params)
    levels = [bands] if prior is not None else list(range(8, bands, 4)) + [bands]
    prior_roots = None if prior is None else prior.energy_roots()
    distribution = _distribution_weights(reflectances * light.mean(axis=0))
    shading = np.ones((photos, fields))
    specularity = np.zeros((photos, fields))
    response_full = None
    iterations = 0
    for count in levels:
        interpolate = _interpolation_matrix(wavelengths, count)
        previous = (
            None
            if response_full is None
            else np.linalg.lstsq(interpolate, response_full, rcond=None)[0]
        )
        for _ in range(max_iterations):
            iterations += 1
            weights = (
                np.ones((fields, 3))
                if response_full is None
                else field_weights(reflectances, light.mean(axis=0), response_full, distribution)
            )
            prior_rows = None
            if prior is not None and prior_roots is not None:
                peaks = (
                    _initial_peaks(rgb, reflectances, light, prior)
                    if response_full is None
                    else np.abs(response_full).max(axis=0)
                )
                prior_rows = _prior_rows(prior_roots, interpolate, peaks, params["prior"])
            coarse, shading = _solve_response_and_shading(
                fixed, specularity, weights, interpolate, previous, prior_rows
            )
            new_full = interpolate @ coarse
            specularity = _solve_specularity(rgb, reflectances, light, shading, weights, new_full)
            change = (
                np.inf
                if response_full is None
                else np.abs(new_full - response_full).max() / max(np.abs(new_full).max(), 1e-12)
            )
            response_full, previous = new_full, coarse
            if change < tolerance:
                break
    if response_full is None:
        raise InputError(f"max_iterations: expected at least 1, got {max_iterations}")
    return response_full, shading, specularity, iterations


@dataclass(frozen=True)
class _FixedTerms:
    """What stays fixed through the iterations: the normalized photographs ``rgb`` (P, J, 3),
    the reflectances, the lights (P, K), the Laplacian of neighbouring fields (Eq. 9.9 is
    :math:`\\beta F^T \\Delta F`) and the weights of the terms."""

    rgb: np.ndarray
    reflectances: np.ndarray
    light: np.ndarray
    laplacian: np.ndarray
    params: dict[str, float]


def _solve_response_and_shading(
    fixed: _FixedTerms,
    specularity: np.ndarray,
    weights: np.ndarray,
    interpolate: np.ndarray,
    previous: np.ndarray | None,
    prior_rows: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """One linear least-squares step for (R coarse, F) with sigma fixed (Eq. 9.6 without sigma),
    with the prior's rows ``(3, K, count)`` when there are any.

    The unknowns are the coarse responses of the three channels, then the shading factors of
    each photograph. The normal equations are assembled block by block (each data row touches
    one channel's response and one field's shading): the same solution as stacking the rows of
    every term, without forming that tall, mostly empty matrix.
    """
    rgb, light, params = fixed.rgb, fixed.light, fixed.params
    photos, fields, _ = rgb.shape
    count = interpolate.shape[1]
    shading_start = 3 * count
    normal = np.zeros((shading_start + photos * fields,) * 2)
    right = np.zeros(shading_start + photos * fields)
    for photo in range(photos):
        reflected = (fixed.reflectances + specularity[photo][:, None]) * light[photo]  # (J, K)
        projected = reflected @ interpolate  # (J, count)
        shading = slice(shading_start + photo * fields, shading_start + (photo + 1) * fields)
        diagonal = np.zeros(fields)
        for channel in range(3):
            # Data rows of Eq. 9.7: sqrt(w) (projected R_c - F_j D_jc).
            weight = params["data"] * weights[:, channel]
            response = slice(channel * count, (channel + 1) * count)
            normal[response, response] += projected.T @ (weight[:, None] * projected)
            cross = -(projected * (weight * rgb[photo, :, channel])[:, None]).T  # (count, J)
            normal[response, shading] += cross
            normal[shading, response] += cross.T
            diagonal += weight * rgb[photo, :, channel] ** 2
        normal[shading, shading] += params["beta"] * fixed.laplacian + np.diag(diagonal)
    for channel in range(3):
        reference = None if previous is None else previous[:, channel]
        border = np.zeros((2, count))
        border[0, 0] = border[1, -1] = np.sqrt(params["delta"])
        terms = [  # (rows on R_c, their targets): Eq. 9.8, 9.11, the prior, Eq. 9.10
            (np.sqrt(params["alpha"]) * _smoothness_rows(count, reference), 0.0),
            (border, 0.0),
        ]
        if prior_rows is not None:
            terms.append((prior_rows[channel], 0.0))
        if reference is not None:
            terms.append(
                (np.sqrt(params["gamma"]) * np.eye(count), np.sqrt(params["gamma"]) * reference)
            )
        response = slice(channel * count, (channel + 1) * count)
        for rows, target in terms:
            normal[response, response] += rows.T @ rows
            right[response] += rows.T @ np.broadcast_to(target, rows.shape[0])
    # The mean shading is one: a single heavy row over all shading factors.
    mean_row = 1e3 / (photos * fields)
    normal[shading_start:, shading_start:] += mean_row**2
    right[shading_start:] += mean_row * 1e3
    solution = _solve_normal_equations(normal, right)
    coarse = solution[:shading_start].reshape(3, count).T
    return coarse, solution[shading_start:].reshape(photos, fields)


def _solve_normal_equations(normal: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Least-squares solution from its normal equations (Cholesky), the minimum-norm solution
    if they are singular.

    The systems of Eq. 9.6 are well conditioned (condition number about 250 for the Nikon D70
    on 240 fields, so about 6e4 for the normal equations): the Cholesky solve agrees with
    ``numpy.linalg.lstsq`` on the stacked rows to 1e-12.
    """
    try:
        return linalg.cho_solve(linalg.cho_factor(normal), right)
    except linalg.LinAlgError:
        return np.linalg.lstsq(normal, right, rcond=None)[0]


def _solve_specularity(
    rgb: np.ndarray,
    reflectances: np.ndarray,
    light: np.ndarray,
    shading: np.ndarray,
    weights: np.ndarray,
    response: np.ndarray,
) -> np.ndarray:
    """Closed-form sigma_j >= 0 per photo and field with R and F fixed (Eq. 9.7)."""
    specularity = np.empty(shading.shape)
    for photo in range(rgb.shape[0]):
        white = light[photo] @ response  # (3,): response to a wavelength-independent reflectance
        diffuse = (reflectances * light[photo]) @ response  # (J, 3)
        residual = shading[photo][:, None] * rgb[photo] - diffuse  # (J, 3)
        numerator = np.sum(weights * residual * white, axis=1)
        denominator = np.sum(weights * white**2, axis=1)
        specularity[photo] = np.clip(numerator / np.maximum(denominator, 1e-12), 0.0, 1.0)
    return specularity


def _normalized(rgb: np.ndarray, light: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Each photograph's device RGB ``(P, J, 3)`` and light ``(P, K)`` divided by their means
    (thesis 9.4.2), and the units of the response: those of the first photograph."""
    rgb_scale = rgb.mean(axis=(1, 2), keepdims=True)
    light_scale = light.mean(axis=1, keepdims=True)
    if np.any(rgb_scale <= 0) or np.any(light_scale <= 0):
        raise InputError("chart_rgb, illuminant: expected some signal in every photograph")
    return rgb / rgb_scale, light / light_scale, float(rgb_scale[0, 0, 0] / light_scale[0, 0])


@overload
def estimate_response(
    chart_rgb: np.ndarray,
    reflectances: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    *,
    method: str = "extended",
    field_positions: np.ndarray | None = None,
    alpha: float | None = None,
    beta: float = 100.0,
    gamma: float = 1.0,
    delta: float = 10.0,
    data_weight: float = 300.0,
    max_iterations: int = 50,
    tolerance: float = 3e-4,
    prior: ResponsePrior | MeasuredPrior | None = "measured",
    prior_weight: float = PRIOR_WEIGHT,
    return_details: Literal[False] = False,
) -> np.ndarray: ...
@overload
def estimate_response(
    chart_rgb: np.ndarray,
    reflectances: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    *,
    method: str = "extended",
    field_positions: np.ndarray | None = None,
    alpha: float | None = None,
    beta: float = 100.0,
    gamma: float = 1.0,
    delta: float = 10.0,
    data_weight: float = 300.0,
    max_iterations: int = 50,
    tolerance: float = 3e-4,
    prior: ResponsePrior | MeasuredPrior | None = "measured",
    prior_weight: float = PRIOR_WEIGHT,
    return_details: Literal[True],
) -> CharacterizationResult: ...
def estimate_response(
    chart_rgb: np.ndarray,
    reflectances: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    *,
    method: str = "extended",
    field_positions: np.ndarray | None = None,
    alpha: float | None = None,
    beta: float = 100.0,
    gamma: float = 1.0,
    delta: float = 10.0,
    data_weight: float = 300.0,
    max_iterations: int = 50,
    tolerance: float = 3e-4,
    prior: ResponsePrior | MeasuredPrior | None = "measured",
    prior_weight: float = PRIOR_WEIGHT,
    return_details: bool = False,
) -> np.ndarray | CharacterizationResult:
    """Effective spectral response :math:`R^{eff}` ``(K, 3)`` from chart photographs.

    Parameters
    ----------
    chart_rgb
        Linear, dark-subtracted mean device RGB of each field: ``(J, 3)`` for one photograph or
        ``(P, J, 3)`` for several.
    reflectances
        Field reflectances ``(J, K)`` in [0, 1] on ``wavelengths``.
    illuminant
        Relative spectral power of the light: ``(K,)`` or one ``(P, K)`` row per photograph.
    wavelengths
        The ``K`` sample wavelengths in nm.
    method
        ``"basic"`` (Eq. 9.3-9.5) or ``"extended"`` (Eq. 9.6-9.14).
    field_positions
        ``(J, 2)`` field centres on the chart (any unit) for the shading neighbourhoods of
        Eq. 9.9; required by ``"extended"``.
    alpha, beta, gamma, delta
        Weights of smoothness, shading smoothness, damping and border. The thesis uses
        3, 500, 1, 10 without saying how large its field weights are; here the data term is
        multiplied by ``data_weight`` (field weights have mean 2). ``beta = 100`` with
        ``data_weight = 300`` is the best of a 4 x 4 grid (beta 30-500, data_weight 100-3000)
        on scenarios the tests do not use: the Nikon 5100 and Aptina MT9M131 under D50 and D75
        on a 240-field and the 113-field Esser chart in shuffled layouts, specularity in
        [0, 0.1] and shading in [0.8, 1.2] drawn from seeds 1000-1003 (mean 6.7 % of the peak
        over 32 scenarios; ``benchmarks/camchar_tuning.py``). On the tested scenarios (D65,
        the same disturbances from seeds 0-7) the script prints, for the worst channel's RMSE
        as a fraction of the peak: Nikon D70 mean 5.5 %, worst draw 7.4 %, Nikon D100 5.3 %
        and 7.0 % on the 240-field chart; 6.4 % and 8.9 %, 6.4 % and 9.4 % on the Esser chart.
        The thesis's ``beta = 500`` (with ``data_weight = 300``) averages 6.0 % and 5.8 %, and
        8.7 % and 8.2 %. ``alpha`` defaults to 3 for ``"extended"`` and to 1e-6 for
        ``"basic"`` (the thesis gives none for Eq. 9.5; larger values bias ideal data by percent).
    data_weight
        Factor on the data term of the extended energy (see above).
    max_iterations, tolerance
        Alternating least squares per multigrid level: stop when the response changes by less
        than ``tolerance`` relative to its peak.
    prior
        ``"measured"`` (the default): the prior learned from the 51 measured cameras shipped with
        spectwin (:func:`measured_response_prior`); a :class:`recon.camera_prior.ResponsePrior`
        on ``wavelengths`` (e.g. learned from cameras other than the one characterized); or
        None for the thesis's method. Only the extended method takes a prior: ``"basic"``
        ignores the default. With a prior the energy is Eq. 9.6 plus :math:`\\lambda \\sum_c
        E_{prior}(R_c) / (\\max R'_c)^2` (``recon.camera_prior``; :math:`R'` the previous
        estimate as in Eq. 9.8, at first the multiple of the prior's mean that explains the
        mean device RGB), and the alternating least squares runs at full resolution from the
        start. Each of the 51 cameras left out of its prior (learned from the other 50), on
        240 fields and on the 24-patch ColorChecker under CIE D65, A and FL11, two draws each:
        the prior lowers the mean and the largest error in every scenario and makes a camera
        worse by more than 0.5 points only under A in one draw (two Sony cameras on 240 fields,
        three on the ColorChecker, by 0.65 to 2.7 points; ``benchmarks/camchar_prior_loo.py``,
        BENCHMARKS.md).
    prior_weight
        :math:`\\lambda`. The default (``recon.camera_prior.PRIOR_WEIGHT`` = 0.01, with 3
        principal components) has the lowest sum of mean and largest error on scenarios that
        neither the study nor the tests use: each of the 51 measured cameras left out of its
        prior in turn, 240 measured fields under D50 and D75, disturbances from seeds 1000 and
        1001 (mean 3.2 %, largest 4.8 % of the peak; ``benchmarks/camchar_prior_tuning.py``).
        Heavier priors lower the mean and raise the error of the cameras least like the
        others (0.1: 2.8 % and 6.1 %).
    return_details
        Return a :class:`CharacterizationResult` with shading and specularity as well.

    Returns
    -------
    numpy.ndarray or CharacterizationResult
        :math:`R^{eff}` on ``wavelengths``, channels R, G, B.
    """
    rgb, reflectances, light, wavelengths = _as_photos(
        chart_rgb, reflectances, illuminant, wavelengths
    )
    rgb_n, light_n, units = _normalized(rgb, light)
    if isinstance(prior, str) and prior != "measured":
        raise InputError(f"prior: expected 'measured', a ResponsePrior or None, got {prior!r}")
    if prior is not None and prior != "measured" and method != "extended":
        raise InputError(f"prior: only the extended method takes a prior, not {method!r}")
    if method == "basic":
        response = _basic(rgb_n, reflectances, light_n, 1e-6 if alpha is None else alpha) * units
        if not return_details:
            return response
        return CharacterizationResult(response, np.ones(rgb.shape[:2]), np.zeros(rgb.shape[:2]), 1)
    if method != "extended":
        raise InputError(f"method: expected 'basic' or 'extended', got {method!r}")
    if field_positions is None:
        raise InputError("field_positions: the extended method needs the (J, 2) field centres")
    positions = np.asarray(field_positions, np.float64)
    if positions.shape != (reflectances.shape[0], 2):
        raise InputError(
            f"field_positions: expected ({reflectances.shape[0]}, 2), got {positions.shape}"
        )
    params = {
        "alpha": 3.0 if alpha is None else alpha,
        "beta": beta,
        "gamma": gamma,
        "delta": delta,
        "data": data_weight,
        "prior": prior_weight,
    }
    if isinstance(prior, str):  # "measured"
        prior = measured_response_prior(wavelengths)
    if prior is not None:
        _check_prior(prior, wavelengths, prior_weight)
    # Hundreds of small least-squares solves: BLAS threads cost more than they bring (and
    # stall badly when another process holds a core).
    with threadpool_limits(1, user_api="blas"):
        response, shading, specularity, iterations = _extended(
            rgb_n,
            reflectances,
            light_n,
            wavelengths,
            positions,
            params,
            max_iterations,
            tolerance,
            prior,
        )
    response = response * units
    if not return_details:
        return response
    return CharacterizationResult(response, shading, specularity, iterations)


def fit_residuals(
    chart_rgb: np.ndarray,
    reflectances: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    result: CharacterizationResult,
) -> np.ndarray:
    """What the fitted model of Eq. 9.7 leaves unexplained, per photograph, field and channel.

    Parameters
    ----------
    chart_rgb, reflectances, illuminant, wavelengths
        The inputs of :func:`estimate_response` that gave ``result``.
    result
        Its :class:`CharacterizationResult` (``return_details=True``).

    Returns
    -------
    numpy.ndarray
        ``(P, J, 3)``: the device RGB that the model predicts, :math:`\\sum_i (S_{i,j} +
        \\sigma_j) L_i R^{eff}_{i,c} / F_j` (Eq. 9.7 solved for :math:`D_{j,c}`), minus the
        measured :math:`D_{j,c}`, both in units of the photograph's mean device RGB (thesis
        9.4.2). The basic method's result has no shading (one) and no specularity (zero): its
        residuals are those of Eq. 9.4.
    """
    rgb, reflectances, light, wavelengths = _as_photos(
        chart_rgb, reflectances, illuminant, wavelengths
    )
    rgb_n, light_n, units = _normalized(rgb, light)
    if result.response.shape != (wavelengths.size, 3) or result.shading.shape != rgb.shape[:2]:
        raise InputError(
            f"result: expected a response ({wavelengths.size}, 3) and shading {rgb.shape[:2]}, "
            f"got {result.response.shape} and {result.shading.shape}"
        )
    reflected = (reflectances[None] + result.specularity[:, :, None]) * light_n[:, None, :]
    predicted = (reflected @ (result.response / units)) / result.shading[:, :, None]
    return predicted - rgb_n


def _check_prior(prior: ResponsePrior, wavelengths: np.ndarray, weight: float) -> None:
    if not isinstance(prior, ResponsePrior):
        raise InputError(
            f"prior: expected a ResponsePrior (recon.camera_prior), got {type(prior).__name__}"
        )
    if not np.array_equal(prior.wavelengths_nm, wavelengths):
        raise InputError(
            f"prior: learned on {prior.wavelengths_nm.size} wavelengths "
            f"({prior.wavelengths_nm[0]:g}-{prior.wavelengths_nm[-1]:g} nm), expected the "
            f"estimate's {wavelengths.size} ({wavelengths[0]:g}-{wavelengths[-1]:g} nm)"
        )
    if not weight > 0:
        raise InputError(f"prior_weight: expected a positive weight, got {weight}")


def reference_response(
    band_rgb: np.ndarray,
    band_transmissions: np.ndarray,
    white_reflectance: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    *,
    sigma_nm: float = 7.0,
) -> np.ndarray:
    """The monochromator reference (Eq. 9.15-9.16): camera RGB of a white target through each
    LCTF band ``(n_bands, 3)``, band transmissions ``(n_bands, K)``; pseudo-inverse of the
    transmissions, division by white x light, Gaussian smoothing of ``sigma_nm``."""
    wavelengths = np.asarray(wavelengths, np.float64)
    transmissions = np.asarray(band_transmissions, np.float64)
    band_rgb = np.asarray(band_rgb, np.float64)
    if transmissions.shape[1] != wavelengths.size or band_rgb.shape != (transmissions.shape[0], 3):
        raise InputError(
            "band_rgb, band_transmissions: expected (n_bands, 3) and (n_bands, K) on the grid"
        )
    product = np.linalg.pinv(transmissions) @ band_rgb  # R (.) rho (.) L
    response = (
        product / np.maximum(np.asarray(white_reflectance) * np.asarray(illuminant), 1e-12)[:, None]
    )
    step = float(np.mean(np.diff(wavelengths)))
    return ndimage.gaussian_filter1d(response, sigma_nm / step, axis=0, mode="nearest")


def prediction_error(
    response: np.ndarray, reflectances: np.ndarray, illuminant: np.ndarray, chart_rgb: np.ndarray
) -> np.ndarray:
    """Per-field difference between predicted and measured device RGB (Eq. 9.17), ``(J, 3)``."""
    predicted = (np.asarray(reflectances) * np.asarray(illuminant)) @ np.asarray(response)
    return np.abs(predicted - np.asarray(chart_rgb))


def profile_matrix(
    response: np.ndarray, illuminant: np.ndarray, observer: np.ndarray
) -> np.ndarray:
    """3x3 matrix from device RGB to XYZ under ``illuminant`` (Eq. 9.18):
    :math:`M = (R^{eff} \\odot L)^+ (M_{XYZ} \\odot L)`; apply as ``xyz = rgb @ M``."""
    light = np.asarray(illuminant, np.float64)[:, None]
    return np.linalg.pinv(np.asarray(response) * light) @ (np.asarray(observer) * light)
