"""Camera characterization across the 51 measured cameras, each left out of the prior that
guides its estimate (thesis chapter 9 on real cameras).

One spectral photograph of a 240-field chart of measured reflectances
(``twin.components.targets.camera_chart_reflectances``) under CIE D65, disturbed as in thesis
9.4.2: per-field specularity uniform in [0, 0.1] added to the reflectance and a smooth shading
:math:`1 + 0.2 \\sin(2x + a) \\cos(1.5y + b)` in [0.8, 1.2] over the chart's 20 x 12 layout. The
photograph is simulated at the cameras' 5 nm sampling; a camera's device RGB is that spectral
image times its measured sensitivities (the response is linear in the spectrum, so one image
serves every camera), scaled to a mean of one, plus Gaussian noise of 0.5 % of that mean. The
estimators work on 380-780 nm in 10 nm cells (cell means of the 5 nm data).

Per camera, three methods on the same device RGB:

- ``prior``: the extended estimator (Eq. 9.6-9.14) with the prior of ``recon.camera_prior``
  learned from the other 50 cameras;
- ``extended``: the thesis's extended estimator without prior;
- ``jiang2013``: Jiang et al. (2013) through colour-science, its basis learned from the same
  other 50 cameras.

Error: the worst channel's RMSE after one global scale, in percent of the true peak
(``recon.metrics.peak_relative_rmse``).
"""

from __future__ import annotations

import csv
import time
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import colour
import numpy as np
from scipy import stats

from recon.camera_char import estimate_response
from recon.camera_jiang2013 import jiang2013_response
from recon.camera_prior import PRIOR_COMPONENTS, PRIOR_WEIGHT, learn_response_prior
from recon.chart_photos.charts import colorchecker_reflectances
from recon.errors import InputError
from recon.measured_data import camera_name, camera_names, read_camera_sensitivities
from recon.metrics import peak_relative_rmse
from recon.progress import progress_steps
from recon.spectra import WavelengthGrid, from_colour, resample
from twin.components.targets import camera_chart_reflectances
from twin.output_format import dumps
from twin.studies.camchar_figures import errors_figure, response_curves_figure

__all__ = [
    "BOUNDS_PCT",
    "CHARTS",
    "ESTIMATION_GRID",
    "METHODS",
    "CameraCharacterization",
    "characterize_cameras",
    "run_camchar_cameras",
]

ESTIMATION_GRID = WavelengthGrid.regular(380.0, 780.0, 10.0)
PHOTO_GRID = WavelengthGrid.regular(380.0, 780.0, 5.0)
CHARTS = {"240": 20, "colorchecker": 6}
"""The charts (columns of their layout): the 240 measured fields, 20 x 12, and the ColorChecker
Classic (isetbio's measurement, ``recon.chart_photos.charts``), 6 x 4."""
SPECULARITY_MAX = 0.1
SHADING_AMPLITUDE = 0.2
NOISE = 0.005
LIGHT = "D65"
METHODS = ("prior", "extended", "jiang2013")
BOUNDS_PCT = {"mean": 4.0, "max": 7.0}  # the goal for the method with prior


@dataclass(frozen=True)
class _Chart:
    """The spectral photograph shared by all cameras and what the estimators are told."""

    image: np.ndarray  # (J, K5) radiance per field, PHOTO_GRID
    reflectances: np.ndarray  # (J, K) on ESTIMATION_GRID
    illuminant: np.ndarray  # (K,) on ESTIMATION_GRID
    positions: np.ndarray  # (J, 2) column, row


@dataclass(frozen=True)
class CameraCharacterization:
    """One camera's estimates and their errors."""

    camera: str
    truth: np.ndarray  # (K, 3) on ESTIMATION_GRID
    estimates: dict[str, np.ndarray]  # method -> (K, 3)
    errors_pct: dict[str, float]  # method -> worst channel's error
    prior_energy: float  # the truth's E_prior under its leave-one-out prior, summed over channels


def _light(name: str, grid: WavelengthGrid) -> np.ndarray:
    spectrum = from_colour(colour.SDS_ILLUMINANTS[name])
    return resample(spectrum, grid, method="box").values


def _reflectances(chart: str, grid: WavelengthGrid) -> np.ndarray:
    if chart == "colorchecker":
        return resample(colorchecker_reflectances(), grid, method="box").values
    return camera_chart_reflectances(grid).values


def _chart(seed: int, light: str, chart: str = "240") -> _Chart:
    fine = _reflectances(chart, PHOTO_GRID)
    fields = len(fine)
    columns = CHARTS[chart]
    positions = np.array([[j % columns, j // columns] for j in range(fields)], float)
    rng = np.random.default_rng(seed)
    specularity = rng.uniform(0.0, SPECULARITY_MAX, fields)
    phase = rng.uniform(0.0, 3.0, 2)
    x, y = positions.T / positions.max()
    shading = 1 + SHADING_AMPLITUDE * np.sin(2 * x + phase[0]) * np.cos(1.5 * y + phase[1])
    image = shading[:, None] * (fine + specularity[:, None]) * _light(light, PHOTO_GRID)
    return _Chart(
        image=image,
        reflectances=_reflectances(chart, ESTIMATION_GRID),
        illuminant=_light(light, ESTIMATION_GRID),
        positions=positions,
    )


def _photograph(chart: _Chart, sensitivities: np.ndarray, camera: str, seed: int) -> np.ndarray:
    """Device RGB ``(J, 3)`` of ``camera`` (sensitivities ``(K5, 3)``): mean one, noisy; the
    noise is drawn from ``seed`` and the camera's name, so a camera's photograph does not depend
    on which other cameras are characterized."""
    rgb = chart.image @ sensitivities
    rgb = rgb / rgb.mean()
    rng = np.random.default_rng([seed, zlib.crc32(camera.encode())])
    return np.clip(rgb + NOISE * rng.standard_normal(rgb.shape), 0.0, None)


def _estimate(
    method: str, rgb: np.ndarray, chart: _Chart, others, prior, prior_weight: float
) -> np.ndarray:
    """The response ``(K, 3)`` that ``method`` estimates from the device RGB ``rgb``."""
    wavelengths = ESTIMATION_GRID.wavelengths_nm
    if method == "jiang2013":
        return jiang2013_response(rgb, chart.reflectances, chart.illuminant, wavelengths, others)
    return estimate_response(
        rgb,
        chart.reflectances,
        chart.illuminant,
        wavelengths,
        field_positions=chart.positions,
        prior=prior if method == "prior" else None,
        prior_weight=prior_weight,
    )


def _error_pct(estimate: np.ndarray, truth: np.ndarray) -> float:
    return float(100 * peak_relative_rmse(estimate, truth).max())


def characterize_cameras(
    cameras: Sequence[str] | None = None,
    *,
    seed: int = 0,
    light: str = LIGHT,
    chart: str = "240",
    methods: Sequence[str] = METHODS,
    components: int = PRIOR_COMPONENTS,
    prior_weight: float = PRIOR_WEIGHT,
    progress: bool = False,
) -> list[CameraCharacterization]:
    """Estimate the response of each camera in ``cameras`` (all 51 by default) by ``methods``
    (module description), every prior and basis learned from the other 50 cameras.

    Parameters
    ----------
    cameras
        Names from ``recon.measured_data.camera_names``.
    seed
        Draws the specularity and shading of the chart and, with each camera's name, its noise.
    light
        A CIE illuminant of ``colour.SDS_ILLUMINANTS`` (the study's is D65).
    chart
        One of :data:`CHARTS` (the study's is the 240-field chart).
    methods
        A subset of :data:`METHODS`.
    components, prior_weight
        The prior's principal components per channel (``recon.camera_prior``) and its weight
        :math:`\\lambda` in ``recon.camera_char.estimate_response``.
    progress
        Show a progress bar.
    """
    everyone = camera_names()
    cameras = list(everyone) if cameras is None else [camera_name(name) for name in cameras]
    if not cameras:
        raise InputError("cameras: expected at least one measured camera")
    if not methods or set(methods) - set(METHODS):
        raise InputError(f"methods: expected some of {METHODS}, got {tuple(methods)}")
    if chart not in CHARTS:
        raise InputError(f"chart: expected one of {sorted(CHARTS)}, got {chart!r}")
    if light not in colour.SDS_ILLUMINANTS:
        raise InputError(f"light: expected a CIE illuminant such as 'D65', got {light!r}")
    measured = {name: read_camera_sensitivities(name) for name in everyone}
    fine = {name: resample(s, PHOTO_GRID).values.T for name, s in measured.items()}
    responses = {
        name: resample(s, ESTIMATION_GRID, method="box", out_of_range="clamp").values.T
        for name, s in measured.items()
    }
    photographed = _chart(seed, light, chart)
    results = []
    with progress_steps("characterizing cameras", len(cameras), enabled=progress) as advance:
        for camera in cameras:
            others = np.array([responses[name] for name in everyone if name != camera])
            prior = learn_response_prior(
                others, ESTIMATION_GRID.wavelengths_nm, components=components
            )
            rgb = _photograph(photographed, fine[camera], camera, seed)
            estimates = {
                m: _estimate(m, rgb, photographed, others, prior, prior_weight) for m in methods
            }
            truth = responses[camera]
            results.append(
                CameraCharacterization(
                    camera=camera,
                    truth=truth,
                    estimates=estimates,
                    errors_pct={m: _error_pct(e, truth) for m, e in estimates.items()},
                    prior_energy=float(prior.energy(truth).sum()),
                )
            )
            advance()
    return results


def _statistics(results: list[CameraCharacterization], method: str) -> dict[str, Any]:
    errors = np.array([result.errors_pct[method] for result in results])
    hardest = np.argsort(errors)[::-1][:3]
    return {
        "mean_pct": round(float(errors.mean()), 2),
        "median_pct": round(float(np.median(errors)), 2),
        "max_pct": round(float(errors.max()), 2),
        "cameras_over_5_pct": int(np.sum(errors > 5.0)),
        "hardest": {results[i].camera: round(float(errors[i]), 2) for i in hardest},
    }


def _write_table(path: Path, results: list[CameraCharacterization], methods) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["camera", *(f"{m}_error_pct" for m in methods), "prior_energy_of_truth"])
        for result in results:
            writer.writerow(
                [
                    result.camera,
                    *(f"{result.errors_pct[m]:.2f}" for m in methods),
                    f"{result.prior_energy:.0f}",
                ]
            )


def run_camchar_cameras(
    out_dir: Path,
    *,
    cameras: Sequence[str] | None = None,
    seed: int = 0,
    progress: bool = False,
) -> dict[str, Any]:
    """Characterize the cameras (module description) and write ``table.csv`` (per camera and
    method), ``errors.png`` (per-camera errors), ``worst_camera.png`` (the curves of the camera
    hardest for the method with prior) and ``summary.json``; return the summary."""
    started = time.perf_counter()
    results = characterize_cameras(cameras, seed=seed, progress=progress)
    out_dir.mkdir(parents=True, exist_ok=True)
    _write_table(out_dir / "table.csv", results, METHODS)
    names = [result.camera for result in results]
    errors = {m: np.array([r.errors_pct[m] for r in results]) for m in METHODS}
    labels = {
        "prior": "extended + prior (other 50 cameras)",
        "extended": "extended (thesis)",
        "jiang2013": "Jiang 2013 (colour)",
    }
    errors_figure(
        names,
        {labels[m]: errors[m] for m in METHODS},
        f"leave-one-out over {len(names)} cameras: 240 fields, D65, seed {seed}",
        bounds_pct={f"goal: {k} {v:g} %": v for k, v in BOUNDS_PCT.items()},
    ).savefig(out_dir / "errors.png", dpi=110)
    worst = results[int(np.argmax(errors["prior"]))]
    response_curves_figure(
        ESTIMATION_GRID.wavelengths_nm,
        worst.truth,
        {labels[m]: worst.estimates[m] for m in METHODS},
        f"{worst.camera}: the hardest camera for the estimate with prior",
    ).savefig(out_dir / "worst_camera.png", dpi=110)
    energies = np.array([r.prior_energy for r in results])
    summary = {
        "cameras": len(results),
        "chart": "240 measured reflectances (camera_chart_reflectances), 20 x 12 fields",
        "light": LIGHT,
        "disturbance": "specularity U[0, 0.1], shading in [0.8, 1.2], noise 0.5 % of the mean",
        "seed": seed,
        "grid_nm": [ESTIMATION_GRID.start_nm, ESTIMATION_GRID.stop_nm, 10.0],
        "methods": {m: _statistics(results, m) for m in METHODS},
        "bounds_pct_of_prior": BOUNDS_PCT,
        # Whether the hardest cameras are those least like the others.
        "rank_correlation_prior_error_vs_prior_energy": round(
            float(stats.spearmanr(errors["prior"], energies).statistic), 2
        ),
        "seconds": round(time.perf_counter() - started, 1),
        "outputs": ["table.csv", "errors.png", "worst_camera.png", "summary.json"],
    }
    (out_dir / "summary.json").write_text(dumps(summary))
    return summary
