"""What the twin of a real bench fits, and only on the frames its bench file declares.

- The chart's pose, from its patch label image (geometry, not radiometry): OpenCV's
  ``solvePnP`` on the patch centres, scaled to the bench's chart distance.
- The lamp: its power behind each filter (the lamp's spectrum inside a 10 nm passband is not in
  the data) and, where the bench asks, its position, on the fit patches' pixels at one exposure
  per filter (the longest at which most of their channel means lie in ``[min_dn, max_dn]``).
  The stored value of a pixel of a Lambertian chart is :math:`p = t P_f S_{f,c} K E(L)/E(L_0)`
  (thesis Eq. 3.1 without the dark signal, which is fitted apart): exposure time, the lamp's
  power behind filter :math:`f`, the rendered photo-electron rate of the pixel's channel
  :math:`c` for a unit lamp at :math:`L_0`, the gain into stored digital numbers, and the ratio
  of the irradiance :math:`E = \\cos\\theta / r^2` that a point lamp at :math:`L` and at
  :math:`L_0` gives the chart point the pixel sees. Log residuals, least squares
  (``scipy.optimize.least_squares``) from several starting positions.
- The dark current, its log-normal spread across pixels (DSNU) and the defect pixels (a
  fraction with an extra offset at every exposure), on the dark frames of
  ``fit.dark_exposures_ms``, by the mean stored value, its spatial spread and the fraction of
  stored pixels above zero.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage
from scipy.optimize import least_squares

from recon.chart_patches import patch_statistics
from recon.errors import DamagedDataError, MissingDataError
from twin.rigs.bench_config import BenchConfig
from twin.rigs.camera_config import CameraConfig
from twin.sensor.model import Sensor, mosaic_channels
from twin.sensor.reduced_copy import reduce_linear

__all__ = [
    "DarkFit",
    "LampFit",
    "camera_with_dark",
    "chart_points",
    "chart_pose",
    "fit_dark",
    "fit_exposure_index",
    "fit_lamp",
    "lamp_irradiance_ratio",
    "stored_per_raw_dn",
]

_DSNU_GRID = np.arange(0.5, 6.01, 0.5)
_DARK_CURRENT_GRID = np.logspace(-3, 4, 141)
_DEFECT_GRID = np.array([0, 1, 2, 3, 5, 8, 12, 20, 30, 50]) * 1e-6
_DEFECT_OFFSET_GRID = (256.0, 512.0, 1024.0, 2048.0, 4096.0)
_LAMP_STARTS_M = np.array([[0.0, 0.0, 0.0], [-0.3, -0.3, 0.0], [0.3, 0.3, 0.0]])
_FLOOR = 1e-5  # keeps the logarithm of a zero statistic finite


def chart_pose(
    labels: np.ndarray, *, columns: int, distance_m: float, focal_px: float
) -> tuple[np.ndarray, float, float]:
    """The chart's pose in the camera frame from its patch label image.

    The patch centres (label centroids) against the chart's layout (``columns`` per row, unit
    pitch, centred, y up; :func:`twin.materials.calibration_targets.chart_parts`) give the pose
    up to scale (principal point at the image centre, no distortion); the scale puts the chart's
    centre at ``distance_m``.

    Returns
    -------
    pose : numpy.ndarray
        4 x 4 chart-to-camera transform (OpenCV frame), in metres.
    pitch_m : float
        The patch pitch that scale implies.
    rms_px : float
        Root-mean-square distance between the label centroids and the projected patch centres.
    """
    count = int(labels.max())
    rows = -(-count // columns)
    centroids = np.array(ndimage.center_of_mass(np.ones_like(labels), labels, range(1, count + 1)))[
        :, ::-1
    ]
    indices = np.arange(count)
    layout = np.column_stack(
        [
            -columns / 2 + indices % columns + 0.5,
            rows / 2 - indices // columns - 0.5,
            np.zeros(count),
        ]
    )
    height, width = labels.shape
    intrinsics = np.array(
        [[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1]]
    )
    found, rotation_vector, translation = cv2.solvePnP(layout, centroids, intrinsics, None)
    if not found:
        raise DamagedDataError("chart labels: the patch centres fit no pose of the chart")
    projected, _ = cv2.projectPoints(layout, rotation_vector, translation, intrinsics, None)
    rms_px = float(np.sqrt(np.mean(np.sum((projected[:, 0] - centroids) ** 2, axis=1))))
    pitch_m = distance_m / float(np.linalg.norm(translation))
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(rotation_vector)[0]
    pose[:3, 3] = translation[:, 0] * pitch_m
    return pose, pitch_m, rms_px


def chart_points(pose: np.ndarray, focal_px: float, shape: tuple[int, int]) -> np.ndarray:
    """``(H, W, 3)``: the point of the chart's plane each pixel sees, in the camera frame."""
    height, width = shape
    rows, columns = np.mgrid[0:height, 0:width]
    rays = np.stack(
        [
            (columns - (width - 1) / 2) / focal_px,
            (rows - (height - 1) / 2) / focal_px,
            np.ones(shape),
        ],
        axis=-1,
    )
    normal = pose[:3, 2]
    return rays * ((normal @ pose[:3, 3]) / (rays @ normal))[..., None]


def lamp_irradiance_ratio(
    pose: np.ndarray, points: np.ndarray, lamp_m: np.ndarray, reference_m: np.ndarray
) -> np.ndarray:
    """The irradiance :math:`\\cos\\theta / r^2` a point lamp at ``lamp_m`` gives chart-plane
    ``points`` ``(..., 3)`` (:func:`chart_points`), over that of a lamp at ``reference_m``
    (camera frame); zero where the lamp lies behind the chart."""
    irradiance = _point_lamp_irradiance(pose, points)
    return irradiance(lamp_m) / irradiance(reference_m)


def _point_lamp_irradiance(
    pose: np.ndarray, points: np.ndarray
) -> Callable[[np.ndarray], np.ndarray]:
    """The irradiance :math:`\\cos\\theta / r^2` of chart-plane ``points`` as a function of the
    lamp's position (zero where the lamp lies behind the chart)."""
    normal = pose[:3, 2] if pose[:3, 2] @ pose[:3, 3] < 0 else -pose[:3, 2]  # towards the camera

    def irradiance(lamp: np.ndarray) -> np.ndarray:
        towards = np.asarray(lamp, np.float64) - points
        squared = np.sum(towards**2, axis=-1)
        return np.clip(towards @ normal, 0, None) / squared**1.5

    return irradiance


def fit_exposure_index(bench: BenchConfig, means: np.ndarray, exposures: np.ndarray) -> int:
    """Index of the longest exposure at which most of the fit patches' channel means lie in
    ``[min_dn, max_dn]``; ``means`` ``(n_exposures, n_fit_patches, 3)``."""
    inside = (means >= bench.fit.min_dn) & (means <= bench.fit.max_dn)
    counts = inside.reshape(len(exposures), -1).sum(axis=1)
    best = max(range(len(exposures)), key=lambda index: (counts[index], exposures[index]))
    if counts[best] == 0:
        raise MissingDataError(
            f"{bench.name}: no exposure puts a fit patch between {bench.fit.min_dn} and "
            f"{bench.fit.max_dn} DN"
        )
    return best


@dataclass(frozen=True, eq=False)
class LampFit:
    """The fitted lamp: ``position_m`` (camera frame), ``log_power`` per filter (against the
    unit lamp of the render), and per filter the ``fit_exposure_s`` and ``pixels`` used;
    ``rms_log`` is the fit's root-mean-square log residual."""

    position_m: np.ndarray
    log_power: np.ndarray
    fit_exposure_s: np.ndarray
    pixels: np.ndarray
    rms_log: float


@dataclass(frozen=True, eq=False)
class FitPixels:
    """The pixels one filter's lamp fit uses: their flat indices and their log of the stored
    value over :math:`t S_{f,c} K`."""

    flat_index: np.ndarray
    log_ratio: np.ndarray
    exposure_s: float


def fit_pixels(
    bench: BenchConfig,
    frames: np.ndarray,
    exposures: np.ndarray,
    rate_dn: np.ndarray,
    fit_masks: np.ndarray,
    channel_index: np.ndarray,
) -> FitPixels:
    """Choose one filter's fit exposure among its ``frames`` ``(n, H, W)`` and collect the fit
    patches' pixels in ``[min_dn, max_dn]`` (``rate_dn`` ``(H, W, 3)``: stored DN per second)."""
    order = np.argsort(exposures)
    top = 2**bench.reduction.bit_depth - 1
    means = np.array(
        [patch_statistics(frames[k], fit_masks, channel_index, top_dn=top).mean for k in order]
    )
    chosen = order[fit_exposure_index(bench, means, exposures[order])]
    frame = frames[chosen]
    rate = mosaic_channels(rate_dn, channel_index)
    use = fit_masks.any(axis=0) & (frame >= bench.fit.min_dn) & (frame <= bench.fit.max_dn)
    use &= rate > 0
    flat = np.flatnonzero(use)
    ratio = np.log(frame.ravel()[flat]) - np.log(exposures[chosen] * rate.ravel()[flat])
    return FitPixels(flat, ratio, float(exposures[chosen]))


def fit_lamp(
    bench: BenchConfig,
    pixels: list[FitPixels],
    *,
    pose: np.ndarray,
    focal_px: float,
    shape: tuple[int, int],
) -> LampFit:
    """Fit the lamp's power per filter and (with ``lamp.fit_position``) its position, on the
    pixels of :func:`fit_pixels` (module docstring)."""
    reference = np.asarray(bench.lamp.position_m, np.float64)
    filters = len(pixels)
    used, inverse = np.unique(
        np.concatenate([item.flat_index for item in pixels]), return_inverse=True
    )
    points = chart_points(pose, focal_px, shape).reshape(-1, 3)[used]
    observed = np.concatenate([item.log_ratio for item in pixels])
    filter_of = np.repeat(np.arange(filters), [item.flat_index.size for item in pixels])
    # lamp_irradiance_ratio with the reference lamp's irradiance computed once
    irradiance = _point_lamp_irradiance(pose, points)
    at_reference = irradiance(reference)

    @functools.lru_cache(maxsize=4)
    def log_ratio_at(position: bytes) -> np.ndarray:
        """The log irradiance ratio of a lamp position (its float64 bytes): the finite
        differences of the powers ask again for the position they start from."""
        ratio = irradiance(np.frombuffer(position)) / at_reference
        return np.log(np.maximum(ratio, _FLOOR))

    def residuals(parameters: np.ndarray) -> np.ndarray:
        position = parameters[:3] if bench.lamp.fit_position else reference
        log_ratio = log_ratio_at(np.asarray(position, np.float64).tobytes())
        return observed - parameters[3 + filter_of] - log_ratio[inverse]

    powers = np.array([np.mean(item.log_ratio) for item in pixels])
    starts = _LAMP_STARTS_M + reference if bench.lamp.fit_position else reference[None, :]
    best = min(
        (
            least_squares(residuals, np.concatenate([start, powers]), method="lm")
            for start in starts
        ),
        key=lambda solution: solution.cost,
    )
    position = best.x[:3] if bench.lamp.fit_position else reference
    return LampFit(
        position_m=position,
        log_power=best.x[3 : 3 + filters],
        fit_exposure_s=np.array([item.exposure_s for item in pixels]),
        pixels=np.array([item.flat_index.size for item in pixels]),
        rms_log=float(np.sqrt(np.mean(best.fun**2))),
    )


def stored_per_raw_dn(bench: BenchConfig, camera: CameraConfig) -> float:
    """Digital numbers of the stored frames per raw digital number: the reduction maps the raw
    range onto the stored one."""
    return (2**bench.reduction.bit_depth - 1) / (2**camera.bit_depth - 1)


@dataclass(frozen=True, eq=False)
class DarkFit:
    """The fitted dark current (e-/s at the sensor's temperature), DSNU spread, and the fraction
    of defect pixels and their offset (raw DN)."""

    dark_current_e_per_s: float
    dsnu_sigma: float
    defect_pixel_fraction: float = 0.0
    defect_offset_dn: float = 0.0


def camera_with_dark(
    camera: CameraConfig,
    dark_current: float,
    dsnu_sigma: float,
    defect_fraction: float = 0.0,
    defect_offset_dn: float = 0.0,
) -> CameraConfig:
    """``camera`` with the dark current (at its sensor temperature), DSNU spread and defect
    pixels (fraction, offset) set."""
    dark = camera.dark_current.model_copy(
        update={
            "e_per_s_at_reference": dark_current,
            "reference_temperature_c": camera.sensor_temperature_c,
        }
    )
    pattern = camera.fixed_pattern.model_copy(
        update={
            "dsnu_sigma": dsnu_sigma,
            "defect_pixel_fraction": defect_fraction,
            "defect_offset_dn": defect_offset_dn,
        }
    )
    return camera.model_copy(update={"dark_current": dark, "fixed_pattern": pattern})


def fit_dark(
    bench: BenchConfig,
    camera: CameraConfig,
    dark_frames: np.ndarray,
    dark_exposure_s: np.ndarray,
) -> DarkFit:
    """Fit the dark current, its log-normal spread and the defect pixels (their fraction and
    offset) on the dark frames of ``fit.dark_exposures_ms``, by the mean stored value, its
    spatial spread and the fraction of stored pixels above zero (squared log errors).

    A stored dark frame is the reduction of the mean dark electrons
    (:meth:`twin.sensor.Sensor.mean_dark_electrons`, linear in the dark current) plus that of
    the defects' offsets, rounded: one reduction per spread and per defect fraction on their
    grids, then every defect offset and dark current on theirs. Temporal noise is left out of
    the fit (its share of a stored dark pixel is below 0.1 DN after the reduction).
    """
    wanted = np.array(bench.fit.dark_exposures_ms) / 1000
    chosen = np.isclose(dark_exposure_s[:, None], wanted[None, :]).any(axis=1)
    if not chosen.any():
        raise MissingDataError(
            f"{bench.name}: no dark frame at the fit exposures "
            f"{list(bench.fit.dark_exposures_ms)} ms"
        )
    exposures = np.unique(dark_exposure_s[chosen])
    groups = [dark_frames[np.isclose(dark_exposure_s, exposure)] for exposure in exposures]
    measured = np.log(
        np.array([[group.mean(), group.std(), np.mean(group > 0)] for group in groups]) + _FLOOR
    )
    shape = (bench.reduction.height, bench.reduction.width)
    stored_per_raw = stored_per_raw_dn(bench, camera)
    scales = exposures * camera.system_gain_dn_per_e * stored_per_raw
    dark_units, defect_units = _unit_dark_signals(camera.model_dump_json(), shape)
    best = (np.inf, DarkFit(0.0, 0.0))
    for fraction, defects in zip(_DEFECT_GRID, defect_units, strict=True):
        per_offset = defects * stored_per_raw
        touched = per_offset > 1e-9
        for sigma, unit in dark_units.items():
            clean = _SortedTail(unit[~touched])
            for offset in _DEFECT_OFFSET_GRID if fraction > 0 else (0.0,):
                errors = clean.errors(
                    unit[touched], per_offset[touched] * offset, scales, measured, unit.size
                )
                index = int(np.argmin(errors))
                if errors[index] < best[0]:
                    fit = DarkFit(
                        float(_DARK_CURRENT_GRID[index]), float(sigma), float(fraction), offset
                    )
                    best = (errors[index], fit)
    return best[1]


@functools.lru_cache(maxsize=2)
def _unit_dark_signals(
    camera_json: str, shape: tuple[int, int]
) -> tuple[dict[float, np.ndarray], list[np.ndarray]]:
    """The reduced (``shape``, flattened) unit dark signals of a camera (its JSON): the mean
    dark electrons at 1 e-/s for 1 s per DSNU spread of the grid, and the defect pixels at a
    unit offset per defect fraction of the grid (zero where the fraction is). They depend on
    the camera and the reduction alone, so another fit of the same camera reuses them."""
    camera = CameraConfig.model_validate_json(camera_json)
    dark_units = {
        sigma: reduce_linear(
            Sensor(camera_with_dark(camera, 1.0, float(sigma))).mean_dark_electrons(1.0),
            camera.mosaic,
            shape,
        ).ravel()
        for sigma in _DSNU_GRID
    }
    defect_units = []
    for fraction in _DEFECT_GRID:
        if fraction > 0:
            unit_camera = camera_with_dark(camera, 0.0, 0.0, float(fraction), 1.0)
            defects = Sensor(unit_camera).defect_pixels().astype(np.float64)
            defect_units.append(reduce_linear(defects, camera.mosaic, shape).ravel())
        else:  # the reduction of an all-zero frame (float32, as reduce_linear gives)
            defect_units.append(np.zeros(shape[0] * shape[1], np.float32))
    for unit in [*dark_units.values(), *defect_units]:
        unit.flags.writeable = False
    return dark_units, defect_units


class _SortedTail:
    """The unit dark signal of the pixels no defect reaches, sorted, with suffix sums: a stored
    pixel is non-zero from 0.5 DN up, so one search gives how many are, and the suffix sums their
    sum and sum of squares (rounding adds 1/12 DN^2 of variance per pixel above zero)."""

    def __init__(self, values: np.ndarray):
        self.ordered = np.sort(values)
        self.sums = np.concatenate([np.cumsum(self.ordered[::-1])[::-1], [0.0]])
        self.squares = np.concatenate([np.cumsum(self.ordered[::-1] ** 2)[::-1], [0.0]])

    def errors(
        self,
        touched: np.ndarray,
        defect_dn: np.ndarray,
        scales: np.ndarray,
        measured: np.ndarray,
        count: int,
    ) -> np.ndarray:
        """Squared log errors of (mean, spread, above zero) for every dark current of the grid;
        ``touched`` and ``defect_dn`` are the unit dark signal and defect offset (stored DN) of
        the pixels a defect reaches, computed exactly."""
        errors = np.zeros(_DARK_CURRENT_GRID.size)
        for scale, target in zip(scales, measured, strict=True):
            scaled = _DARK_CURRENT_GRID * scale  # stored DN per unit dark signal, per current
            start = np.searchsorted(self.ordered, 0.5 / scaled)
            above = self.ordered.size - start
            near = np.rint(defect_dn[None, :] + touched[None, :] * scaled[:, None])
            total = scaled * self.sums[start] + near.sum(axis=1)
            squares = scaled**2 * self.squares[start] + above / 12 + np.sum(near**2, axis=1)
            mean = total / count
            spread = np.sqrt(np.clip(squares / count - mean**2, 0.0, None))
            nonzero = (above + np.count_nonzero(near, axis=1)) / count
            predicted = np.log(np.stack([mean, spread, nonzero], axis=1) + _FLOOR)
            errors += np.sum((predicted - target) ** 2, axis=1)
        return errors
