"""``spectwin dome-study``: the thesis's chapter 10 experiments on the twin LED dome."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from twin.cli.choices import DomeMaterial
from twin.cli.errors import fail, require_output_folder
from twin.cli.output import JsonFlag, console, print_summary

__all__ = ["register"]


def dome_study(
    out: Annotated[Path, typer.Option(help="Folder for dome_study.json and the PNGs.")] = Path(
        "dome_study"
    ),
    texels: Annotated[
        int,
        typer.Option(min=8, max=256, help="Texture side in texels (a multiple of 4)."),
    ] = 32,
    materials: Annotated[
        list[DomeMaterial] | None,
        typer.Option("--material", help="A material to study (repeat); default: all four."),
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the cameras' noise.")] = 0,
    dark_frames: Annotated[
        int,
        typer.Option(
            min=1,
            help="Spectral-camera dark frames averaged per exposure time by the analytic "
            "path's dome calibrations (the thesis: 200; fewer calibrate faster and noisier).",
        ),
    ] = 200,
    stores: Annotated[
        Path | None,
        typer.Option(
            help="Folder of the dome-run and dome-calibration stores (captured where missing, "
            "reused where complete); default OUT/stores."
        ),
    ] = None,
    leds: Annotated[
        int, typer.Option(min=1, max=198, help="LEDs of the study's dome captures.")
    ] = 10,
    capture_texels: Annotated[
        int,
        typer.Option(
            min=8,
            max=256,
            help="Texels of the study's dome captures (a Bayer quad each at the top camera; "
            "204: about the rig's own 0.1 mm pixels).",
        ),
    ] = 32,
    capture_spp: Annotated[
        int | None,
        typer.Option(
            min=1,
            max=1024,
            help="Samples per pixel of the study's dome captures (default: the dome "
            "captures' own; captured at three times the processed texels, 4 still give each "
            "texel 36).",
        ),
    ] = None,
    store_texels: Annotated[
        int | None,
        typer.Option(
            min=4,
            max=256,
            help="Texels the dome captures are processed at (default: --capture-texels; "
            "fewer give each texel more of the cameras' pixels).",
        ),
    ] = None,
    analytic_only: Annotated[
        bool, typer.Option(help="Skip the dome captures: frames from the analytic path only.")
    ] = False,
    stores_only: Annotated[
        bool, typer.Option(help="Only the dome captures' experiments (10.4.2, 10.5).")
    ] = False,
    error_budget: Annotated[
        bool,
        typer.Option(
            help="Per material, where the stores' errors come from: the reconstruction, the "
            "cameras' sampling, noise and rendering, registration (each rung solved again; "
            "4-8 more minutes a material at 64 texels on 2 cores)."
        ),
    ] = False,
    as_json: JsonFlag = False,
) -> None:
    """Exposure plan, band schedules, low-SNR calibration, virtual dome captures and their
    spectralization (thesis 10.3-10.5): single and multi-image reconstruction, Dong 2016 and
    Spectral A+, the exposure comparison of 10.5 and the Fig. 10.4 cross-check.

    Example: spectwin dome-study --out out/dome --material lego --material red_fabric
    """
    from dataclasses import replace
    from functools import partial

    from twin.rigs.rig_config import load_rig
    from twin.studies.dome import DOME_MATERIALS, run_dome_study
    from twin.studies.dome_stores import STORE_CAPTURE, store_study

    if texels % 4:
        fail(f"--texels {texels}: expected a multiple of 4")
    if analytic_only and stores_only:
        fail("--analytic-only, --stores-only: expected one of them at most")
    if analytic_only and error_budget:
        fail("--analytic-only, --error-budget: the error budget is the dome stores'")
    require_output_folder(out)
    chosen = tuple(dict.fromkeys(m.value for m in materials)) if materials else DOME_MATERIALS
    capture = replace(STORE_CAPTURE, leds=leds, texels=capture_texels)
    if capture_spp is not None:
        capture = replace(capture, spp=capture_spp)
    if store_texels is not None and store_texels > capture_texels:
        fail(f"--store-texels {store_texels}: expected at most --capture-texels {capture_texels}")
    if not analytic_only:
        capture.check(load_rig("dome"))  # before any work
    with console.status("dome study") as status:
        step = lambda name: status.update(name)  # noqa: E731
        metrics = run_dome_study(
            out,
            texels=texels,
            materials=chosen,
            seed=seed,
            dark_frames=dark_frames,
            analytic=not stores_only,
            store_metrics=None
            if analytic_only
            else partial(
                store_study,
                stores if stores is not None else out / "stores",
                chosen,
                capture,
                seed=seed,
                step=step,
                error_budget=error_budget,
                texels=store_texels,
            ),
            step=step,
        )
    if as_json:
        print_summary(metrics, "", as_json)
        return
    summary: dict[str, object] = {"out": str(out)}
    if "schedules" in metrics:
        summary |= _analytic_summary(metrics)
    if "stores" in metrics:
        summary |= _store_summary(metrics["stores"])
    print_summary(summary, "dome study (thesis chapter 10)")


def _analytic_summary(metrics: dict) -> dict[str, str]:
    """The analytic path's numbers, rounded."""
    summary = {}
    for name, plan in metrics["schedules"].items():
        if isinstance(plan, dict):
            summary[f"schedule {name}"] = (
                f"{plan['n_images']} images, +{plan['increase_pct']:.1f} %"
            )
    for material, result in metrics["materials"].items():
        single, multi = result["single_image"], result["multi_image"]
        summary[f"{material} single image"] = (
            f"{single['mean_relative_error_pct']:.2f} %, Delta E94 {single['mean_delta_e94']:.2f}"
        )
        summary[f"{material} 20 images with / without bands"] = _with_without(multi)
    exposure = metrics["exposure_10_5"]
    summary["10.5 reference spectral capture"] = (
        f"{exposure['reference_total_s']:.0f} s, {exposure['reference_error_pct']:.2f} %"
    )
    for hybrid in exposure["hybrid"]:
        summary[f"10.5 hybrid x{hybrid['scale']:.3g}"] = (
            f"{hybrid['total_s']:.1f} s, {hybrid['error_pct']:.2f} %"
        )
    check = metrics["cross_check_10_4"]
    summary["Fig. 10.4 field difference"] = f"{check['mean_abs_field_difference_pct']:.2f} % mean"
    return summary


def _store_summary(stores: dict) -> dict[str, str]:
    """The store path's numbers next to the analytic path's on the same images, rounded."""
    summary = {}
    for material, result in stores["materials"].items():
        for source in ("stores", "analytic"):
            summary[f"{material} dome stores: with / without bands ({source})"] = _with_without(
                result[source]
            )
            summary[f"{material} edge-free texels: with / without bands ({source})"] = (
                _with_without(result[source]["edge_free"])
            )
            summary[f"{material} same view, edge-free: with / without bands ({source})"] = (
                _same_view(result["view_fixed_shift"][source]["edge_free"])
            )
        if "error_budget" in result:
            budget = result["error_budget"]
            summary[f"{material} error budget, with / without bands"] = ", ".join(
                f"{rung.replace('_', ' ')} {_with_without(budget[rung])}"
                for rung in budget["rungs"]
            )
    ratio = stores["exposure_10_5"]
    summary["10.5 from the stores"] = (
        f"{ratio['reference_total_s']:.0f} s / {ratio['hybrid_total_s']:.1f} s, "
        f"{ratio['orders_of_magnitude']:.2f} orders of magnitude"
    )
    return summary


def _with_without(groups: dict) -> str:
    """Mean relative errors of the images with and without spectral data ("none" where no
    texel was kept)."""
    return " / ".join(
        "none" if groups[name] is None else f"{groups[name]['mean_relative_error_pct']:.2f} %"
        for name in ("with_spectral_data", "without_spectral_data")
    )


def _same_view(cameras: dict) -> str:
    """Per partner camera the mean relative errors of its images with and without the band
    data ("none" where no texel was kept)."""
    return ", ".join(
        f"{camera} none"
        if errors is None
        else f"{camera} {errors['mean_relative_error_pct']['with']:.2f} / "
        f"{errors['mean_relative_error_pct']['without']:.2f} %"
        for camera, errors in cameras.items()
    )


def register(app: typer.Typer) -> None:
    """Add the command to ``app``."""
    app.command(name="dome-study")(dome_study)
