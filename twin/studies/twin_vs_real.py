"""Twin against reality: predict every frame of a real bench capture, then compare.

The twin of the bench (:func:`twin.studies.bench_twin.bench_twin`) fits its free parameters on
the frames the bench file declares (the fit patches at one exposure per filter; the dark frames
of the fit exposures) and predicts every frame: each chart frame is simulated twice (two draws of
the temporal noise) at the camera's full size and reduced as the data set's frames were. Both
real and predicted frames are summarized by the same code (:mod:`recon.chart_patches`): per patch
and Bayer channel the mean, the spatial spread, the fraction of clipped pixels, and for the
prediction the temporal spread (the real capture keeps one frame per setting). The errors are
reported on everything that was not fitted.

Goals (the digital twin's acceptance): median |predicted - measured| / measured within 5 % and
its 95th percentile within 12 % on the unclipped patch means; clipping (a patch channel with at
least 1 % of its pixels at the top value) predicted right for 95 % of patch-exposures.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from recon.chart_patches import PatchStatistics, dark_statistics, patch_statistics
from recon.errors import InputError
from recon.progress import progress_steps
from twin.output_format import dumps
from twin.rigs.bench_config import BenchConfig, load_bench
from twin.studies.bench_twin import (
    BenchTwin,
    RealCapture,
    bench_twin,
    check_bench,
    read_real_capture,
)

__all__ = [
    "CLIPPED_FRACTION",
    "GOALS",
    "FrameComparison",
    "compare_frames",
    "mean_errors",
    "run_twin_vs_real",
]

CLIPPED_FRACTION = 0.01
"""A patch channel counts as clipped when at least this fraction of its pixels is at the top."""

GOALS = {"median": 0.05, "p95": 0.12, "clipping_agreement": 0.95}


@dataclass(frozen=True, eq=False)
class FrameComparison:
    """Measured and predicted statistics of every chart frame: arrays ``(n_frames, n_patches,
    3)`` (R, G, B) and the frames' ``band_nm``, ``exposure_s`` and whether each patch of each
    frame was ``fitted`` ``(n_frames, n_patches)``."""

    band_nm: np.ndarray
    exposure_s: np.ndarray
    fitted: np.ndarray
    measured: PatchStatistics
    predicted: PatchStatistics
    predicted_temporal: np.ndarray

    def evaluated(self, min_dn: float) -> np.ndarray:
        """``(n_frames, n_patches, 3)`` bool: not fitted, measured unclipped and at least
        ``min_dn`` (below it the stored frames' quantization alone is 5 % or more)."""
        return (
            ~self.fitted[..., None] & (self.measured.clipped == 0) & (self.measured.mean >= min_dn)
        )

    def relative_error(self) -> np.ndarray:
        """``(predicted - measured) / measured`` of the patch means."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return (self.predicted.mean - self.measured.mean) / self.measured.mean


def _stack(statistics: list[PatchStatistics]) -> PatchStatistics:
    """Stack per-frame statistics into ``(n_frames, n_patches, 3)`` arrays."""
    return PatchStatistics(
        *(
            np.stack([getattr(item, field.name) for item in statistics])
            for field in fields(PatchStatistics)
        )
    )


def _fitted(twin: BenchTwin, band_nm: float, exposure_s: float) -> np.ndarray:
    fit_exposure = twin.lamp.fit_exposure_s[twin.filter_index(band_nm)]
    names = twin.bench.chart.patches
    on_fit_frame = np.isclose(exposure_s, fit_exposure)
    return np.array([on_fit_frame and name in twin.bench.fit.patches for name in names])


def compare_frames(
    twin: BenchTwin,
    real: RealCapture,
    *,
    simulate: bool = True,
    seed: int = 0,
    progress: bool = False,
) -> FrameComparison:
    """Predict every chart frame of ``real`` and summarize both sides.

    With ``simulate`` each frame is simulated twice through the camera model and the reduction
    (its statistics from the first draw, the temporal spread from the pair); without it the
    noise-free frame is used (fast; no temporal spread, clipping at the top value).
    """
    measured, predicted, temporal, fitted = [], [], [], []
    rng = np.random.default_rng(seed)
    top = twin.top_dn
    with progress_steps(
        "predicting the frames", len(real.chart_frames), enabled=progress
    ) as advance:
        for frame, band, exposure in zip(
            real.chart_frames, real.band_nm, real.exposure_s, strict=True
        ):
            measured.append(patch_statistics(frame, twin.masks, twin.channel_index, top_dn=top))
            if simulate:
                first = twin.simulate_frame(band, exposure, rng).astype(np.float64)
                second = twin.simulate_frame(band, exposure, rng).astype(np.float64)
                noise = patch_statistics(
                    (first - second) / np.sqrt(2), twin.masks, twin.channel_index, top_dn=np.inf
                )
                temporal.append(noise.spread)
            else:
                first = np.clip(np.rint(twin.expected_frame(band, exposure)), 0, top)
                temporal.append(np.full((len(twin.masks), 3), np.nan))
            predicted.append(patch_statistics(first, twin.masks, twin.channel_index, top_dn=top))
            fitted.append(_fitted(twin, band, exposure))
            advance()
    return FrameComparison(
        band_nm=real.band_nm,
        exposure_s=real.exposure_s,
        fitted=np.array(fitted),
        measured=_stack(measured),
        predicted=_stack(predicted),
        predicted_temporal=np.array(temporal),
    )


def _error_summary(errors: np.ndarray) -> dict[str, float | int]:
    magnitude = np.abs(errors)
    if magnitude.size == 0:
        return {"n": 0, "median": float("nan"), "p95": float("nan")}
    return {
        "n": int(magnitude.size),
        "median": float(np.median(magnitude)),
        "p95": float(np.percentile(magnitude, 95)),
    }


def mean_errors(comparison: FrameComparison, *, min_dn: float, colour_rows: np.ndarray) -> dict:
    """Errors of the predicted patch means on the evaluated patches: per channel, all channels,
    and the colour patches (``colour_rows``, patch indices) alone; the fitted ones apart."""
    error = comparison.relative_error()
    evaluated = comparison.evaluated(min_dn)
    fit = (
        comparison.fitted[..., None]
        & (comparison.measured.clipped == 0)
        & (comparison.measured.mean >= min_dn)
    )
    colour = np.zeros(evaluated.shape[1], bool)
    colour[colour_rows] = True
    summary = {
        channel: _error_summary(error[..., index][evaluated[..., index]])
        for index, channel in enumerate("RGB")
    }
    summary["all"] = _error_summary(error[evaluated])
    summary["colour_patches"] = _error_summary(error[evaluated & colour[None, :, None]])
    summary["fitted"] = _error_summary(error[fit])
    return summary


def _clipping(comparison: FrameComparison) -> dict:
    evaluated = ~comparison.fitted[..., None] & np.isfinite(comparison.measured.clipped)
    real = comparison.measured.clipped >= CLIPPED_FRACTION
    predicted = comparison.predicted.clipped >= CLIPPED_FRACTION
    agree = (real == predicted)[evaluated]
    pixels = comparison.measured.pixels
    return {
        "patch_exposures": int(agree.size),
        "agreement": float(agree.mean()),
        "measured_clipped": int(real[evaluated].sum()),
        "predicted_clipped": int(predicted[evaluated].sum()),
        "clipped_pixel_fraction_measured": float(
            np.nansum(comparison.measured.clipped * pixels) / np.nansum(pixels)
        ),
        "clipped_pixel_fraction_predicted": float(
            np.nansum(comparison.predicted.clipped * pixels) / np.nansum(pixels)
        ),
    }


def _spread(comparison: FrameComparison, min_dn: float) -> dict:
    evaluated = comparison.evaluated(min_dn)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = comparison.predicted.spread / comparison.measured.spread
        temporal = comparison.predicted_temporal / comparison.predicted.spread
    finite = evaluated & np.isfinite(ratio)
    return {
        "spatial_predicted_over_measured_median": float(np.median(ratio[finite]))
        if finite.any()
        else float("nan"),
        "temporal_share_of_predicted_spatial_median": float(np.nanmedian(temporal[finite]))
        if finite.any() and np.isfinite(temporal[finite]).any()
        else float("nan"),
    }


def _dark_table(twin: BenchTwin, real: RealCapture, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed + 1)
    fit_exposures = np.array(twin.bench.fit.dark_exposures_ms) / 1000
    rows = []
    for exposure in np.unique(real.dark_exposure_s):
        frames = real.dark_frames[np.isclose(real.dark_exposure_s, exposure)]
        simulated = np.stack([twin.simulate_frame(None, exposure, rng) for _ in range(len(frames))])
        measured, predicted = dark_statistics(frames), dark_statistics(simulated)
        rows.append(
            {
                "exposure_ms": float(exposure * 1000),
                "role": "fit" if np.isclose(exposure, fit_exposures).any() else "evaluation",
                "frames": int(len(frames)),
                "measured_mean_dn": measured.mean,
                "predicted_mean_dn": predicted.mean,
                "measured_spread_dn": measured.spread,
                "predicted_spread_dn": predicted.spread,
                "measured_above_zero": measured.above_zero,
                "predicted_above_zero": predicted.above_zero,
                "measured_temporal_dn": measured.temporal_spread,
                "predicted_temporal_dn": predicted.temporal_spread,
            }
        )
    return rows


def _write_patch_table(path: Path, twin: BenchTwin, comparison: FrameComparison) -> None:
    with path.open("w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(
            [
                "band_nm", "exposure_ms", "patch", "channel", "role", "measured_mean_dn",
                "predicted_mean_dn", "measured_spread_dn", "predicted_spread_dn",
                "predicted_temporal_dn", "measured_clipped", "predicted_clipped",
            ]
        )  # fmt: skip
        for frame in range(len(comparison.band_nm)):
            for patch, name in enumerate(twin.bench.chart.patches):
                for channel, letter in enumerate("RGB"):
                    key = (frame, patch, channel)
                    writer.writerow(
                        [
                            int(round(comparison.band_nm[frame])),
                            round(float(comparison.exposure_s[frame]) * 1000, 3),
                            name,
                            letter,
                            "fit" if comparison.fitted[frame, patch] else "evaluation",
                            f"{comparison.measured.mean[key]:.4g}",
                            f"{comparison.predicted.mean[key]:.4g}",
                            f"{comparison.measured.spread[key]:.4g}",
                            f"{comparison.predicted.spread[key]:.4g}",
                            f"{comparison.predicted_temporal[key]:.4g}",
                            f"{comparison.measured.clipped[key]:.4g}",
                            f"{comparison.predicted.clipped[key]:.4g}",
                        ]
                    )


def _fit_report(twin: BenchTwin) -> dict:
    bench = twin.bench
    return {
        "split": {
            "fitted_on": (
                f"patches {', '.join(bench.fit.patches)} at one exposure per filter "
                f"(the longest with most channel means in [{bench.fit.min_dn:g}, "
                f"{bench.fit.max_dn:g}] DN); dark frames at "
                f"{', '.join(str(value) for value in bench.fit.dark_exposures_ms)} ms"
            ),
            "evaluated_on": "every other patch, frame and dark frame",
            "min_dn": bench.fit.min_dn,
            "fit_exposure_ms_per_band": {
                str(band): float(exposure * 1000)
                for band, exposure in zip(twin.bands_nm, twin.lamp.fit_exposure_s, strict=True)
            },
        },
        "fitted": {
            "lamp_position_m": twin.lamp.position_m
            if bench.lamp.fit_position
            else "given: " + str(list(bench.lamp.position_m)),
            "lamp_log_power_per_band": dict(
                zip(map(str, twin.bands_nm), twin.lamp.log_power.tolist(), strict=True)
            ),
            "lamp_fit_rms_log": twin.lamp.rms_log,
            "lamp_fit_pixels": int(twin.lamp.pixels.sum()),
            "dark_current_e_per_s": twin.dark.dark_current_e_per_s,
            "dsnu_sigma": twin.dark.dsnu_sigma,
            "defect_pixel_fraction": twin.dark.defect_pixel_fraction,
            "defect_offset_dn": twin.dark.defect_offset_dn,
        },
        "geometry": {
            "chart_distance_m": bench.chart.distance_m,
            "patch_pitch_m": twin.pitch_m,
            "pose_rms_px": twin.pose_rms_px,
            "chart_normal_camera": twin.pose[:3, 2],
        },
    }


def run_twin_vs_real(
    bench: str | Path | BenchConfig,
    out: Path | None = None,
    *,
    spp: int = 64,
    seed: int = 0,
    bands_nm: tuple[int, ...] | None = None,
    progress: bool = False,
) -> dict:
    """Predict a real bench capture with its twin and compare (module docstring).

    Parameters
    ----------
    bench
        A bench of ``scenes/benches`` by name (e.g. ``"llanos2019"``), a path to one, or a
        loaded bench.
    out
        Folder for ``report.json``, ``patches.csv`` and the figures (none when ``None``).
    spp, seed
        Samples per pixel of the renders; seed of the renders and the simulated noise.
    bands_nm
        Only the frames of these filters (all by default).
    progress
        Show a progress bar.

    Returns
    -------
    dict
        The report (``report.json``).
    """
    from twin.studies.twin_vs_real_figures import write_figures

    bench = bench if isinstance(bench, BenchConfig) else load_bench(bench)
    check_bench(bench)
    real = read_real_capture(bench)
    if bands_nm:
        keep = np.isin(np.round(real.band_nm).astype(int), bands_nm)
        if not keep.any():
            raise InputError(
                f"bands: expected some of {sorted({int(round(b)) for b in real.band_nm})} nm, "
                f"got {list(bands_nm)}"
            )
        real = RealCapture(
            real.chart_frames[keep],
            real.band_nm[keep],
            real.exposure_s[keep],
            real.dark_frames,
            real.dark_exposure_s,
        )
    with progress_steps("rendering the bench and fitting its twin", 1, enabled=progress) as done:
        twin = bench_twin(bench, real, spp=spp, seed=seed)
        done()
    comparison = compare_frames(twin, real, simulate=True, seed=seed, progress=progress)
    colour_rows = np.array(
        [index for index, name in enumerate(bench.chart.patches) if name not in bench.fit.patches]
    )
    errors = mean_errors(comparison, min_dn=bench.fit.min_dn, colour_rows=colour_rows)
    clipping = _clipping(comparison)
    dark = _dark_table(twin, real, seed)
    report = {
        "bench": bench.name,
        "camera": twin.camera.name,
        "frames": int(len(real.chart_frames)),
        "dark_frames": int(len(real.dark_frames)),
        **_fit_report(twin),
        "mean_error": errors,
        "clipping": clipping,
        "spread": _spread(comparison, bench.fit.min_dn),
        "dark": dark,
        "goals": {
            "median_within": GOALS["median"],
            "p95_within": GOALS["p95"],
            "clipping_agreement_at_least": GOALS["clipping_agreement"],
            "median_met": errors["all"]["median"] <= GOALS["median"],
            "p95_met": errors["all"]["p95"] <= GOALS["p95"],
            "clipping_met": clipping["agreement"] >= GOALS["clipping_agreement"],
        },
    }
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        _write_patch_table(out / "patches.csv", twin, comparison)
        report["figures"] = write_figures(out, twin, real, comparison, dark)
        (out / "report.json").write_text(dumps(report))
    return report
