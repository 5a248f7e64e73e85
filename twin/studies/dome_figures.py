"""Figures of the chapter 10 dome study (:mod:`twin.studies.dome`), one PNG each.

Named after the thesis figures they reproduce: ``fig10_5_plan.png`` (band exposures, filter
sizes, the 10-image schedule), ``fig10_7_single_image_errors.png`` (relative error and Delta E94
histograms), ``fig10_9_spectra.png`` (true, reconstructed and noisy band values of selected
texels), ``fig10_13_multi_image.png`` (with and without spectral data),
``fig10_23_comparison.png`` (Dong 2016, Spectral A+), ``fig10_4_cross_check.png``,
``exposure_vs_error.png`` (10.5), ``stores_vs_analytic.png`` (the store path) and
``error_budget.png`` (where the store path's errors come from). Each figure is
a :class:`matplotlib.figure.Figure` of its own: nothing here touches pyplot's global state.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from recon.calibration.dome_capture import DomeCalibration
from twin.dome.capture import THESIS_BANDS_NM
from twin.dome.setup import DomeSetup

__all__ = [
    "write_comparison",
    "write_cross_check",
    "write_error_budget",
    "write_error_histograms",
    "write_measured_spectra",
    "write_exposure_vs_error",
    "write_plan",
    "write_store_comparison",
    "write_texel_spectra",
]


def write_error_histograms(
    groups: dict[str, dict[str, np.ndarray]], title: str, path: Path
) -> None:
    """Relative error and Delta E94 histograms, one row per group, mean as a black line."""
    fig = Figure(figsize=(9, 2.2 * len(groups)))
    axes = fig.subplots(len(groups), 2, squeeze=False)
    for row, (name, values) in enumerate(groups.items()):
        for column, (key, label, limit) in enumerate(
            (("relative", "relative error (%)", 20.0), ("delta_e", "Delta E94", 4.0))
        ):
            data = values[key]
            axis = axes[row, column]
            axis.hist(np.clip(data, 0, limit), bins=40, range=(0, limit), color="tab:blue")
            axis.axvline(data.mean(), color="black")
            axis.set_title(f"{name}: mean {data.mean():.2f}", fontsize=9)
            axis.set_xlabel(label, fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_texel_spectra(results: Mapping[str, Any], path: Path) -> None:
    """Per material, four texels of its first image: truth, reconstruction, noisy bands.

    ``results`` maps material names to :class:`twin.studies.dome.SingleImage` results.
    """
    fig = Figure(figsize=(4 * len(results), 3.2))
    axes = fig.subplots(1, len(results), squeeze=False)
    for axis, (material, result) in zip(axes[0], results.items(), strict=True):
        capture, cube, errors = result.captures[0], result.cubes[0], result.errors[0]
        noisy = capture.band_values()[0]
        candidates = np.flatnonzero(errors.material[0].ravel())
        texels = candidates[np.linspace(0, candidates.size - 1, 4).astype(int)]
        for index, texel in enumerate(texels):
            row, column = np.unravel_index(texel, errors.material[0].shape)
            colour = f"C{index}"
            axis.plot(THESIS_BANDS_NM, capture.truth[0, row, column], color=colour)
            axis.plot(THESIS_BANDS_NM, cube[0, row, column], "--", color=colour)
            axis.plot(THESIS_BANDS_NM, noisy[row, column], ".", color=colour, alpha=0.5)
        axis.set_title(f"{material}: true (line), reconstructed (dashed), bands (dots)", fontsize=8)
        axis.set_xlabel("wavelength (nm)")
    axes[0, 0].set_ylabel("reflectance factor")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_plan(setup: DomeSetup, plans: dict, path: Path) -> None:
    """Fig. 10.5 (exposures and filter sizes per band) and the 10-image schedule."""
    fig = Figure(figsize=(14, 3.4))
    axes = fig.subplots(1, 3)
    axes[0].bar(THESIS_BANDS_NM, setup.exposures_s, width=8)
    axes[0].axhline(plans["rgb_set_s"], color="black", label="RGB set 3.402 s")
    axes[0].set(xlabel="band (nm)", ylabel="t_lambda (s)", title="exposure times")
    axes[0].legend(fontsize=8)
    axes[1].bar(THESIS_BANDS_NM, 5 * setup.filter_sigma(), width=8, color="tab:orange")
    axes[1].set(xlabel="band (nm)", ylabel="filter size (texels)", title="filter sizes (5 sigma)")
    schedule = plans["10_images"]
    bottom = np.zeros(schedule["n_images"])
    for image, bands in enumerate(schedule["images"]):
        for band in bands:
            axes[2].bar(image, setup.exposures_s[band], bottom=bottom[image], color="tab:green")
            label = str(int(THESIS_BANDS_NM[band]))
            middle = bottom[image] + setup.exposures_s[band] / 2
            axes[2].text(image, middle, label, ha="center", va="center", fontsize=6)
            bottom[image] += setup.exposures_s[band]
    axes[2].axhline(plans["rgb_set_s"], color="black")
    axes[2].set(
        xlabel="RGB image",
        ylabel="band exposures (s)",
        title=f"10 images: +{schedule['increase_pct']:.1f} % (thesis +61 %)",
    )
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_cross_check(check: dict, path: Path) -> None:
    """Fig. 10.4: measured RGB, RGB predicted from the spectral image, their difference."""
    measured, predicted = check["measured"], check["predicted"]
    top = np.percentile(measured, 99.5)
    fig = Figure(figsize=(11, 3.8))
    axes = fig.subplots(1, 3)
    for axis, image, title in (
        (axes[0], measured, "(a) RGB measured"),
        (axes[1], predicted, "(b) RGB from the spectral image"),
    ):
        axis.imshow(np.clip(image / top, 0, 1) ** 0.5)
        axis.set_title(title, fontsize=9)
    difference = np.abs(predicted - measured).sum(-1) / measured.sum(-1).clip(1e-3) * 100
    shown = axes[2].imshow(difference, vmin=0, vmax=5, cmap="magma")
    axes[2].set_title(
        f"(c) |difference| (%), fields: mean {check['mean_abs_field_difference_pct']:.2f} %",
        fontsize=9,
    )
    fig.colorbar(shown, ax=axes[2])
    for axis in axes:
        axis.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_exposure_vs_error(exposure: dict, path: Path) -> None:
    """Thesis 10.5: mean relative error against total exposure, spectral camera alone and hybrid."""
    fig = Figure(figsize=(6, 4))
    axis = fig.subplots()
    axis.loglog(
        exposure["spectral_only_totals_s"],
        exposure["spectral_only_errors_pct"],
        "o-",
        label="spectral camera only (80 % fill, /4, /16, /64)",
    )
    hybrid = exposure["hybrid"]
    axis.loglog(
        [h["total_s"] for h in hybrid],
        [h["error_pct"] for h in hybrid],
        "s-",
        label="RGB + noisy bands, Eq. 10.12",
    )
    axis.loglog(
        [h["spectral_s"] for h in hybrid],
        [h["direct_error_pct"] for h in hybrid],
        "^:",
        label="the hybrid's noisy bands used as they are",
    )
    axis.set(
        xlabel="total exposure (s)",
        ylabel="mean relative error (%)",
        title=f"thesis 10.5, colour checker, {exposure['pixels_per_texel']} px per texel",
    )
    axis.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_comparison(metrics: dict, path: Path) -> None:
    """Mean relative error and Delta E94 per method and material (Fig. 10.23's means)."""
    materials = list(metrics["materials"])
    methods = ("spectralization", "dong", "a_plus")
    fig = Figure(figsize=(11, 3.6))
    axes = fig.subplots(1, 2)
    for axis, key, label in (
        (axes[0], "mean_relative_error_pct", "mean relative error (%)"),
        (axes[1], "mean_delta_e94", "mean Delta E94"),
    ):
        for offset, method in enumerate(methods):
            values = [metrics["materials"][m]["comparison"][method][key] for m in materials]
            axis.bar(np.arange(len(materials)) + 0.27 * (offset - 1), values, 0.27, label=method)
        axis.set_xticks(np.arange(len(materials)), materials)
        axis.set_ylabel(label)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_store_comparison(stores: dict, path: Path) -> None:
    """10.4.2 from capture stores against the analytic path on the same images: mean relative
    error with and without spectral data per material, over the material texels and over the
    edge-free ones (none kept: no bar), and 10.5's exposure totals."""
    materials = list(stores["materials"])
    bars = [
        (source, group)
        for source in ("analytic", "stores")
        for group in ("with_spectral_data", "without_spectral_data")
    ]
    fig = Figure(figsize=(12, 3.8))
    panels = fig.subplots(1, 2, sharey=True)
    width = 0.8 / len(bars)
    for axis, texels, title in zip(
        panels,
        (lambda errors: errors, lambda errors: errors["edge_free"]),
        ("material texels", "edge-free texels (truth uniform over 3 x 3)"),
        strict=True,
    ):
        for offset, (source, group) in enumerate(bars):
            kept = [texels(stores["materials"][m][source])[group] for m in materials]
            values = [np.nan if e is None else e["mean_relative_error_pct"] for e in kept]
            axis.bar(
                np.arange(len(materials)) + width * (offset - 1.5),
                values,
                width,
                label=f"{source}, {group.replace('_', ' ')}",
            )
        axis.set_xticks(np.arange(len(materials)), materials)
        axis.set_yscale("log")
        axis.set_title(title, fontsize=9)
    panels[0].set_ylabel("mean relative error (%)")
    ratio = stores["exposure_10_5"]
    fig.suptitle(
        f"same images, analytic and from dome stores; 10.5 from the stores: "
        f"{ratio['reference_total_s']:.0f} s / {ratio['hybrid_total_s']:.1f} s = "
        f"{ratio['orders_of_magnitude']:.2f} orders",
        fontsize=9,
    )
    panels[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_error_budget(stores: dict, path: Path) -> None:
    """Per material the error budget's rungs (:mod:`twin.studies.dome_budget`), mean relative
    error with and without spectral data, next to the analytic path on the same images; no
    figure where no material has a budget."""
    budgets = {m: r["error_budget"] for m, r in stores["materials"].items() if "error_budget" in r}
    if not budgets:
        return
    rungs = next(iter(budgets.values()))["rungs"]
    fig = Figure(figsize=(12, 3.8))
    panels = fig.subplots(1, 2, sharey=True)
    width = 0.8 / (len(rungs) + 1)
    for axis, group in zip(panels, ("with_spectral_data", "without_spectral_data"), strict=True):
        for offset, rung in enumerate(rungs):
            axis.bar(
                np.arange(len(budgets)) + width * (offset - len(rungs) / 2),
                [budget[rung][group]["mean_relative_error_pct"] for budget in budgets.values()],
                width,
                label=rung.replace("_", " "),
            )
        axis.bar(
            np.arange(len(budgets)) + width * len(rungs) / 2,
            [stores["materials"][m]["analytic"][group]["mean_relative_error_pct"] for m in budgets],
            width,
            label="analytic path, same images",
            color="grey",
        )
        axis.set_xticks(np.arange(len(budgets)), list(budgets))
        axis.set_yscale("log")
        axis.set_title(group.replace("_", " "), fontsize=9)
    panels[0].set_ylabel("mean relative error (%)")
    panels[0].legend(fontsize=7)
    fig.suptitle("error budget of the dome stores: each rung adds one source of error", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def write_measured_spectra(calibration: DomeCalibration, path: Path) -> None:
    """The spectra a dome calibration measured: the LED spectrum on the white standard (its
    standard error, times ten, shaded) and every RGB camera's response from its chart photograph
    (one line style per camera)."""
    fig = Figure(figsize=(10, 3.6))
    led_axis, camera_axis = fig.subplots(1, 2)
    led = calibration.led_spectrum
    led_axis.plot(led.wavelengths_nm, led.values, color="black")
    led_axis.fill_between(
        led.wavelengths_nm,
        led.values - 10 * led.uncertainty,
        led.values + 10 * led.uncertainty,
        color="tab:orange",
        alpha=0.5,
        label="standard error x 10",
    )
    led_axis.set_title(f"LED spectrum on the white standard ({led.readings} readings)", fontsize=9)
    led_axis.set_xlabel("wavelength (nm)")
    led_axis.legend(fontsize=8)
    styles = ("-", "--", ":", "-.")
    for index, (camera, measured) in enumerate(calibration.camera_response.items()):
        for channel, colour in enumerate(("tab:red", "tab:green", "tab:blue")):
            camera_axis.plot(
                calibration.bands_nm,
                measured.values[:, channel],
                color=colour,
                linestyle=styles[index % len(styles)],
                label=f"{camera} (fit {measured.fit_residual_pct:.1f} %)" if channel == 0 else None,
            )
    camera_axis.set_title("RGB cameras' responses from the chart (peak one)", fontsize=9)
    camera_axis.set_xlabel("wavelength (nm)")
    camera_axis.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
