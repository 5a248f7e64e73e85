"""Figures of a twin-against-reality comparison: predicted against measured patch means, the
residuals laid out as the chart per filter and pixel by pixel, the dark frames, and one real
frame beside its prediction."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from twin.studies.bench_twin import BenchTwin, RealCapture
from twin.studies.twin_vs_real import FrameComparison

__all__ = ["write_figures"]

_CHANNEL_COLOURS = ("tab:red", "tab:green", "tab:blue")


def _scatter(path: Path, twin: BenchTwin, comparison: FrameComparison) -> None:
    figure = Figure(figsize=(6.5, 6))
    axes = figure.add_subplot()
    evaluated = comparison.evaluated(twin.bench.fit.min_dn)
    measured, predicted = comparison.measured.mean, comparison.predicted.mean
    for channel, colour in enumerate(_CHANNEL_COLOURS):
        chosen = evaluated[..., channel]
        axes.scatter(
            measured[..., channel][chosen],
            predicted[..., channel][chosen],
            s=8,
            color=colour,
            alpha=0.6,
            label=f"{'RGB'[channel]} evaluated",
        )
    fitted = (
        comparison.fitted[..., None]
        & (comparison.measured.clipped == 0)
        & (comparison.measured.mean >= twin.bench.fit.min_dn)
    )
    axes.scatter(measured[fitted], predicted[fitted], s=14, marker="x", color="k", label="fitted")
    line = np.array([1.0, 2.0 * twin.top_dn])
    axes.plot(line, line, "k-", lw=0.8)
    axes.fill_between(line, line * 0.88, line * 1.12, color="0.85", label="within 12 %")
    axes.set(
        xscale="log",
        yscale="log",
        xlim=(1, 1.2 * twin.top_dn),
        ylim=(1, 1.2 * twin.top_dn),
        xlabel="measured patch mean (DN)",
        ylabel="predicted patch mean (DN)",
        title=f"{twin.bench.name}: every frame, patch and channel",
    )
    axes.legend(loc="upper left", fontsize=8)
    figure.savefig(path, dpi=110, bbox_inches="tight")


def _residual_map(
    path: Path, twin: BenchTwin, real: RealCapture, comparison: FrameComparison
) -> None:
    """Top row: per filter, the median residual of each patch over its evaluated exposures and
    channels, laid out as the chart. Bottom row: the noise-free prediction against the real
    fit frame, pixel by pixel on the patches (a spatial trend shows a missing illumination or
    vignetting term)."""
    bands = twin.bands_nm
    columns = twin.bench.chart.columns
    count = len(twin.bench.chart.patches)
    rows = -(-count // columns)
    figure = Figure(figsize=(2.6 * len(bands), 5.4))
    error = comparison.relative_error()
    error = np.where(comparison.evaluated(twin.bench.fit.min_dn), error, np.nan)
    image = None
    for index, band in enumerate(bands):
        frames = np.flatnonzero(np.isclose(comparison.band_nm, band))
        per_patch = np.full(rows * columns, np.nan)
        for patch in range(count):
            values = error[frames, patch].ravel()
            if np.isfinite(values).any():
                per_patch[patch] = np.nanmedian(values)
        axes = figure.add_subplot(2, len(bands), index + 1)
        image = axes.imshow(per_patch.reshape(rows, columns), cmap="RdBu_r", vmin=-0.5, vmax=0.5)
        for cell, value in enumerate(per_patch):
            if np.isfinite(value):
                axes.text(
                    cell % columns, cell // columns, f"{value:+.2f}", ha="center", va="center",
                    fontsize=6,
                )  # fmt: skip
        axes.set(title=f"{band} nm, per patch", xticks=[], yticks=[])
        exposure = twin.lamp.fit_exposure_s[index]
        fit_frame = frames[np.isclose(comparison.exposure_s[frames], exposure)][0]
        frame = real.chart_frames[fit_frame].astype(np.float64)
        usable = twin.masks.any(axis=0) & (frame >= twin.bench.fit.min_dn) & (frame < twin.top_dn)
        with np.errstate(divide="ignore", invalid="ignore"):
            residual = np.where(usable, twin.expected_frame(band, exposure) / frame - 1, np.nan)
        pixels = figure.add_subplot(2, len(bands), len(bands) + index + 1)
        pixels.imshow(residual, cmap="RdBu_r", vmin=-0.5, vmax=0.5)
        pixels.set(title=f"pixels, {1000 * exposure:g} ms", xticks=[], yticks=[])
    if image is not None:
        label = "(predicted - measured) / measured"
        figure.colorbar(image, ax=figure.axes, shrink=0.6, label=label)
    figure.savefig(path, dpi=100, bbox_inches="tight")


def _dark(path: Path, dark: list[dict]) -> None:
    figure = Figure(figsize=(10, 4))
    exposure = np.array([row["exposure_ms"] for row in dark])
    fit = np.array([row["role"] == "fit" for row in dark])
    for index, (key, label) in enumerate(
        (
            ("mean_dn", "mean (DN)"),
            ("spread_dn", "spatial spread (DN)"),
            ("above_zero", "pixels above 0"),
        )
    ):
        axes = figure.add_subplot(1, 3, index + 1)
        measured = np.array([row[f"measured_{key}"] for row in dark])
        predicted = np.array([row[f"predicted_{key}"] for row in dark])
        axes.plot(exposure, measured, "ko", label="measured")
        axes.plot(exposure[~fit], predicted[~fit], "s", color="tab:orange", label="predicted")
        axes.plot(
            exposure[fit], predicted[fit], "s", mfc="none", color="tab:orange", label="fitted on"
        )
        axes.set(xscale="log", yscale="log", xlabel="exposure (ms)", title=label)
    figure.axes[0].legend(fontsize=8)
    figure.suptitle("dark frames")
    figure.savefig(path, dpi=100, bbox_inches="tight")


def _frames(path: Path, twin: BenchTwin, real: RealCapture, index: int) -> None:
    band, exposure = real.band_nm[index], real.exposure_s[index]
    measured = real.chart_frames[index].astype(np.float64)
    predicted = twin.simulate_frame(band, exposure, np.random.default_rng(0)).astype(np.float64)
    figure = Figure(figsize=(13, 3.8))
    for column, (image, title) in enumerate(
        (
            (measured, "measured"),
            (predicted, "predicted"),
            (predicted - measured, "predicted - measured"),
        )
    ):
        axes = figure.add_subplot(1, 3, column + 1)
        if column < 2:
            shown = axes.imshow(image, cmap="gray", vmin=0, vmax=twin.top_dn)
        else:
            shown = axes.imshow(image, cmap="RdBu_r", vmin=-40, vmax=40)
        figure.colorbar(shown, ax=axes, shrink=0.8, label="DN")
        axes.set(title=f"{title}, {band:g} nm, {1000 * exposure:g} ms", xticks=[], yticks=[])
    figure.savefig(path, dpi=100, bbox_inches="tight")


def write_figures(
    out: Path, twin: BenchTwin, real: RealCapture, comparison: FrameComparison, dark: list[dict]
) -> list[str]:
    """Write the comparison's figures into ``out``; returns their file names."""
    _scatter(out / "predicted_vs_measured.png", twin, comparison)
    _residual_map(out / "residual_map.png", twin, real, comparison)
    _dark(out / "dark.png", dark)
    middle = len(twin.bands_nm) // 2
    index = int(
        np.flatnonzero(
            np.isclose(real.band_nm, twin.bands_nm[middle])
            & np.isclose(real.exposure_s, twin.lamp.fit_exposure_s[middle])
        )[0]
    )
    _frames(out / "frame.png", twin, real, index)
    return ["predicted_vs_measured.png", "residual_map.png", "dark.png", "frame.png"]
