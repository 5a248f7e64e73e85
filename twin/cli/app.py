"""The ``spectwin`` command line (typer). Commands that compute figures have ``--json``.

Every option is checked before any work starts; a user error prints one line ``error: ...``
to stderr (exit 2 for usage errors, 1 for failed runs), see :mod:`twin.cli.errors`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from twin.cli.bench import register as register_bench
from twin.cli.btf import register as register_btf
from twin.cli.camchar import register as register_camchar
from twin.cli.camera import register as register_camera
from twin.cli.capture import register as register_capture
from twin.cli.dome import register as register_dome
from twin.cli.errors import (
    INTERRUPT_REPORT,
    SpectwinGroup,
    interrupted,
    require_output_folder,
    run_failed,
)
from twin.cli.frames import register as register_frames
from twin.cli.lab import register as register_lab
from twin.cli.material import register as register_material
from twin.cli.output import JsonFlag, SeedOption, console, print_summary
from twin.cli.pipeline import register as register_pipeline
from twin.cli.spectralize import register as register_spectralize
from twin.cli.store import register as register_store
from twin.cli.sweep import register as register_sweep

app = typer.Typer(
    cls=SpectwinGroup,
    help="spectwin: a simulation-first digital twin of spectral reflectance capture rigs.",
    no_args_is_help=True,
    add_completion=False,
)


@app.command()
def info(as_json: JsonFlag = False) -> None:
    """Show the Mitsuba variant spectwin uses, the LLVM it found and the thread count."""
    from twin.render.variant import activate

    print_summary(activate().as_dict(), "spectwin renderer", as_json)


@app.command()
def smoke(
    out: Annotated[Path, typer.Option(help="Folder for the EXR, PNGs and summary.json.")] = Path(
        "out/smoke"
    ),
    pixels_per_patch: Annotated[
        int, typer.Option(min=4, max=256, help="Pixels per chart patch.")
    ] = 24,
    spp: Annotated[int, typer.Option(min=1, max=65536, help="Samples per pixel.")] = 256,
    as_json: JsonFlag = False,
) -> None:
    """Render a ColorChecker under the QTH lamp through the LCTF bands and check it against
    the closed form: PASS or FAIL (exit 1) with the tolerance."""
    from twin.validate.smoke import run_smoke

    require_output_folder(out)
    with console.status("rendering the smoke scene"):
        summary = run_smoke(out, pixels_per_patch=pixels_per_patch, spp=spp)
    verdict = (
        f"{summary['verdict']}: largest relative band error vs closed form "
        f"{100 * summary['max_abs_relative_error']:.2f} % (tolerance "
        f"{100 * summary['tolerance']:.0f} %)"
    )
    if as_json:
        print_summary(summary, "smoke render", as_json)
    else:
        height, width = summary["image_px"]
        console.print(
            f"[bold]smoke render[/bold] {width}x{height} px, {summary['bands']} bands, "
            f"{summary['spp']} spp, variant {summary['variant']['variant']}, "
            f"{summary['render_s']:.2f} s"
        )
        console.print(f"wrote {', '.join(str(out / name) for name in summary['outputs'])}")
    if summary["verdict"] != "PASS":
        run_failed(f"smoke render {verdict}; more --spp lowers the render noise")
    if not as_json:
        console.print(verdict)


@app.command()
def estimate(
    rig: Annotated[str, typer.Argument(help="Rig file in scenes/rigs (gonio, dome) or a path.")],
    as_json: JsonFlag = False,
) -> None:
    """Estimate the capture time of one material on a rig (thesis 4.1.1 and 10.2.2): the dome's
    from its calibration and run plans (HDR sets and scheduled bands per LED, cameras in
    parallel), against the thesis's figures."""
    from twin.kinds.registry import config_rig_kind
    from twin.rigs.rig_config import load_rig

    config = load_rig(rig)
    with console.status("timing the capture plans"):
        outcome = config_rig_kind(config).estimate(config)
    summary = {"rig": config.name, **outcome.summary}
    print_summary(summary, outcome.title, as_json, skip=("rig", "band_exposures_s"))


@app.command()
def gallery(
    out: Annotated[Path, typer.Option(help="Folder for the PNGs and gallery.json.")] = Path(
        "out/gallery"
    ),
    pixels: Annotated[
        int, typer.Option(min=32, max=2048, help="Rendered frame size (square).")
    ] = 256,
    spp: Annotated[int, typer.Option(min=1, max=65536, help="Samples per pixel.")] = 64,
    seed: SeedOption = 0,
) -> None:
    """Simulate one raw frame of every ground-truth material in every rig, as PNGs."""
    from twin.studies.gallery import run_gallery

    require_output_folder(out)
    with console.status("rendering every material in every rig"):
        summary = run_gallery(out, pixels=pixels, spp=spp, seed=seed)
    console.print(f"wrote {len(summary['outputs'])} frames to {out}")


@app.command(name="spectralize-study")
def spectralize_study(
    out: Annotated[Path, typer.Option(help="Folder for study.json and the PNGs.")] = Path(
        "out/spectralize"
    ),
    texels: Annotated[
        int,
        typer.Option(
            min=32,
            max=512,
            help="Texture size of the twin materials (at least 32: the push-broom lines must "
            "hold the 64 spectra that A+ learns from, the sweeps up to 1000 spots).",
        ),
    ] = 96,
    sweeps: Annotated[bool, typer.Option(help="Run the Fig. 7.9 / 7.10 / 7.6 sweeps.")] = True,
    as_json: JsonFlag = False,
) -> None:
    """Chapter 7: spectralization vs. Imai, Hardeberg, Murakami, Dong and A+ on sparse data."""
    from twin.studies.spectralization import run_study

    require_output_folder(out)
    with console.status("rendering twin textures and running the chapter 7 protocols"):
        summary = run_study(out, texels=texels, sweeps=sweeps)
    if as_json:
        print_summary(summary, "spectralization study", as_json)
        return
    for case, result in summary["cases"].items():
        print_summary(result["whisk_broom"], f"{case}: whisk-broom mean relative error", unit="%")
    console.print(f"wrote {out / 'study.json'} and the figures in {out}")


@app.command()
def demo(
    ctx: typer.Context,
    out: Annotated[
        Path, typer.Option(help="Folder for stores, PNGs, metrics.json, report.html.")
    ] = Path("out/demo"),
    as_json: JsonFlag = False,
) -> None:
    """The whole pipeline at small size on built-in defaults, with an HTML report: gonio
    calibration and measurement of the colour checker, BTF, evaluation against the truth,
    spectralization, Figure 4.6 validation (about 90 s on 2 cores; BENCHMARKS.md, "make demo on
    a cold machine").

    Example: spectwin demo --out out/demo
    """
    from twin.studies.demo import run_demo

    require_output_folder(out)
    stages = ["preparation"]
    ctx.meta[INTERRUPT_REPORT] = lambda: interrupted(
        f"in the demo's {stages[-1]}: {out} holds a part of the demo and no report; run the "
        "same command again to start it over"
    )
    with console.status("demo") as status:

        def step(name: str) -> None:
            stages.append(name)
            status.update(f"demo: {name}")

        metrics = run_demo(out, step=step)
    print_summary(metrics["headline"], "spectwin demo", as_json)
    if not as_json:
        console.print(f"report: {out / 'report.html'}")


register_bench(app)
register_btf(app)
register_camchar(app)
register_camera(app)
register_capture(app)
register_pipeline(app)
register_material(app)
register_dome(app)
register_frames(app)
register_store(app)
register_lab(app)
register_sweep(app)
register_spectralize(app)


if __name__ == "__main__":
    app()
