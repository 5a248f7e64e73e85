"""Run the chapter 10 dome study (:mod:`twin.studies.dome`) and draw its figures.

``run_dome_study(out)`` writes ``dome_study.json`` and PNGs named after the thesis figures they
reproduce: ``fig10_5_plan.png`` (band exposures, filter sizes, the 10-image schedule),
``fig10_7_single_image_errors.png`` (relative error and Delta E94 histograms),
``fig10_9_spectra.png`` (true, reconstructed and noisy band values of selected texels),
``fig10_13_multi_image.png`` (with and without spectral data), ``fig10_23_comparison.png``
(Dong 2016, Spectral A+), ``fig10_4_cross_check.png`` and ``exposure_vs_error.png`` (10.5).

Two imaging scales. The single-image, multi-image and comparison experiments image each
material at its physical size (a 4 cm sample at 32 texels: 12 x 12 spectral-camera pixels per
texel, averaged). The thesis evaluates camera pixels (10.5, Fig. 10.24: pixel spectra), so the
single images are repeated, and the 10.5 exposure comparison run, at ``PER_PIXEL_TEXEL_PX``: one
Bayer quad of the RGB camera and 2 x 2 spectral-camera pixels per texel, where a band's noise is
a pixel's and the filters of Fig. 10.5 matter.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from recon.errors import SpectwinInputError  # noqa: E402
from twin.dome.setup import THESIS_BANDS_NM, DomeSetup, dome_setup  # noqa: E402
from twin.materials import load_material  # noqa: E402
from twin.output_format import dumps  # noqa: E402
from twin.studies.dome import (  # noqa: E402
    SingleImage,
    comparison,
    cross_check,
    exposure_comparison,
    metamer_diagnosis,
    multi_image,
    schedules,
    single_image,
)

__all__ = ["DOME_MATERIALS", "PER_PIXEL_TEXEL_PX", "run_dome_study"]

DOME_MATERIALS = ("lego", "wallpaper", "colorchecker16", "red_fabric")
"""The thesis's four example materials (10.4)."""

PER_PIXEL_TEXEL_PX = 2
"""Camera pixels across a texel in the per-pixel regime (module description)."""


def _histograms(groups: dict[str, dict[str, np.ndarray]], title: str, path: Path) -> None:
    """Relative error and Delta E94 histograms, one row per group, mean as a black line."""
    fig, axes = plt.subplots(len(groups), 2, figsize=(9, 2.2 * len(groups)), squeeze=False)
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
    plt.close(fig)


def _errors_of(result: SingleImage) -> dict[str, np.ndarray]:
    return {
        "relative": np.concatenate([e.relative_pct[e.material] for e in result.errors]),
        "delta_e": np.concatenate([e.delta_e94[e.material] for e in result.errors]),
    }


def _spectra(results: dict[str, SingleImage], path: Path) -> None:
    """Per material, four texels of its first image: truth, reconstruction, noisy bands."""
    fig, axes = plt.subplots(1, len(results), figsize=(4 * len(results), 3.2), squeeze=False)
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
    plt.close(fig)


def _plan(setup: DomeSetup, plans: dict, path: Path) -> None:
    """Fig. 10.5 (exposures and filter sizes per band) and the 10-image schedule."""
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.4))
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
    plt.close(fig)


def _cross_check(check: dict, path: Path) -> None:
    """Fig. 10.4: measured RGB, RGB predicted from the spectral image, their difference."""
    measured, predicted = check["measured"], check["predicted"]
    top = np.percentile(measured, 99.5)
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.8))
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
    plt.close(fig)


def _exposure(exposure: dict, path: Path) -> None:
    fig, axis = plt.subplots(figsize=(6, 4))
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
    plt.close(fig)


def run_dome_study(
    out: str | Path,
    *,
    texels: int = 32,
    materials: Sequence[str] = DOME_MATERIALS,
    seed: int = 0,
    step: Callable[[str], None] = lambda name: None,
) -> dict:
    """Run every experiment of :mod:`twin.studies.dome`, write the JSON and figures to ``out``."""
    unknown = sorted(set(materials) - set(DOME_MATERIALS))
    if unknown or not materials:
        raise SpectwinInputError(
            f"materials: expected some of {list(DOME_MATERIALS)}, got {list(materials)}"
        )
    if texels < 8 or texels % 4:
        raise SpectwinInputError(f"texels: expected a multiple of 4, at least 8, got {texels}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    setups: dict[float, DomeSetup] = {}

    def setup_for(material: str) -> DomeSetup:
        size = load_material(material).size_m
        if size not in setups:
            step(f"calibrating the dome for {size * 100:.2f} cm samples")
            setups[size] = dome_setup(texels, sample_size_m=size, seed=seed)
        return setups[size]

    first = setup_for(materials[0])
    step("calibrating the dome at one Bayer quad per texel")
    per_pixel = dome_setup(texels, texel_px=PER_PIXEL_TEXEL_PX, seed=seed)
    plans = schedules(first)
    metrics: dict = {"texels": texels, "schedules": plans, "materials": {}}
    singles, multis = {}, {}
    for material in materials:
        setup = setup_for(material)
        step(f"{material}: single images")
        singles[material] = single_image(setup, material, rng)
        step(f"{material}: Dong 2016 and Spectral A+")
        compared = comparison(setup, material, singles[material], rng)
        step(f"{material}: 20 images")
        _, errors, multi = multi_image(setup, material, rng)
        multis[material] = errors
        step(f"{material}: single images at one Bayer quad per texel")
        per_pixel_single = single_image(per_pixel, material, rng)
        metrics["materials"][material] = {
            "pixels_per_texel": setup.cameras.pixels_per_texel,
            "single_image": singles[material].summary(),
            "comparison": compared,
            "multi_image": multi,
            "metamer_diagnosis": metamer_diagnosis(setup, singles[material].captures[0]),
            "per_pixel": {
                "pixels_per_texel": PER_PIXEL_TEXEL_PX,
                "single_image": per_pixel_single.summary(),
                "metamer_diagnosis": metamer_diagnosis(per_pixel, per_pixel_single.captures[0]),
            },
        }
    step("exposure comparison (one Bayer quad per texel) and cross-check")
    metrics["exposure_10_5"] = exposure_comparison(per_pixel, "colorchecker16", rng)
    check = cross_check(setup_for("colorchecker16"), rng)
    metrics["cross_check_10_4"] = {
        key: value for key, value in check.items() if key not in ("measured", "predicted")
    }
    metrics["plan"] = {
        "bands_nm": THESIS_BANDS_NM,
        "exposures_s": first.exposures_s,
        "filter_sigma_texels": first.filter_sigma(),
        "grey_relative_noise": first.relative_noise,
    }
    step("figures")
    _plan(first, plans, out / "fig10_5_plan.png")
    _histograms(
        {m: _errors_of(r) for m, r in singles.items()},
        "single images (Eq. 10.12)",
        out / "fig10_7_single_image_errors.png",
    )
    _spectra(singles, out / "fig10_9_spectra.png")
    _histograms(
        {
            f"{material} {label}": {
                "relative": errors.relative_pct[part][errors.material[part]],
                "delta_e": errors.delta_e94[part][errors.material[part]],
            }
            for material, errors in multis.items()
            for label, part in (("with bands", slice(0, 10)), ("without", slice(10, 20)))
        },
        "20 images: 10 with spectral data at 45 degrees, 10 without",
        out / "fig10_13_multi_image.png",
    )
    _comparison_figure(metrics, out / "fig10_23_comparison.png")
    _cross_check(check, out / "fig10_4_cross_check.png")
    _exposure(metrics["exposure_10_5"], out / "exposure_vs_error.png")
    (out / "dome_study.json").write_text(dumps(metrics))
    return metrics


def _comparison_figure(metrics: dict, path: Path) -> None:
    """Mean relative error and Delta E94 per method and material (Fig. 10.23's means)."""
    materials = list(metrics["materials"])
    methods = ("spectralization", "dong_2016", "spectral_a_plus")
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6))
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
    plt.close(fig)
