"""The ``spectwin`` command line (typer). Commands that compute figures have ``--json``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from twin.dome_cli import register as register_dome
from twin.gonio_cli import register as register_gonio

app = typer.Typer(
    help="spectwin: a simulation-first digital twin of spectral reflectance capture rigs.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()

JsonFlag = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]


def _print_table(summary: dict[str, object], title: str, *, skip: tuple[str, ...] = ()) -> None:
    table = Table("quantity", "value", title=title)
    for key, value in summary.items():
        if key not in skip:
            table.add_row(key, str(value))
    console.print(table)


@app.command()
def info(as_json: JsonFlag = False) -> None:
    """Show the Mitsuba variant spectwin uses, the LLVM it found and the thread count."""
    from twin.variant import activate

    report = activate().as_dict()
    if as_json:
        typer.echo(json.dumps(report, indent=2))
        return
    _print_table(report, "spectwin renderer")


@app.command()
def smoke(
    out: Annotated[Path, typer.Option(help="Folder for the EXR, PNGs and summary.json.")] = Path(
        "out/smoke"
    ),
    pixels_per_patch: Annotated[int, typer.Option(min=4, help="Pixels per chart patch.")] = 24,
    spp: Annotated[int, typer.Option(min=1, help="Samples per pixel.")] = 256,
    as_json: JsonFlag = False,
) -> None:
    """Render a ColorChecker under the QTH lamp through the LCTF bands, check the closed form."""
    from twin.smoke import run_smoke

    with console.status("rendering the smoke scene"):
        summary = run_smoke(out, pixels_per_patch=pixels_per_patch, spp=spp)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    height, width = summary["image_px"]
    console.print(
        f"[bold]smoke render[/bold] {width}x{height} px, {summary['bands']} bands, "
        f"{summary['spp']} spp, variant {summary['variant']['variant']}, "
        f"{summary['render_s']:.2f} s"
    )
    error_percent = 100 * summary["max_abs_relative_error"]
    console.print(f"largest relative band error vs closed form: {error_percent:.2f} %")
    console.print(f"wrote {', '.join(str(out / name) for name in summary['outputs'])}")


@app.command()
def camera(
    name: Annotated[str, typer.Argument(help="Camera file in scenes/cameras, e.g. coolsnap_k4.")],
    out: Annotated[
        Path, typer.Option(help="Folder for camera_report.png and summary.json.")
    ] = Path("out/camera"),
    seed: Annotated[int, typer.Option(help="Seed of the simulated frames.")] = 0,
    as_json: JsonFlag = False,
) -> None:
    """Bench-test a camera: photon transfer, dark frames, HMI flicker vs exposure time."""
    from twin.camera_report import run_camera_report

    with console.status(f"simulating {name}"):
        summary = run_camera_report(name, out / name, seed=seed)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    _print_table(summary, str(summary["camera"]), skip=("camera", "outputs"))
    console.print(f"wrote {out / name / 'camera_report.png'}")


@app.command()
def estimate(
    rig: Annotated[str, typer.Argument(help="Rig file in scenes/rigs (gonio, dome) or a path.")],
    as_json: JsonFlag = False,
) -> None:
    """Estimate the capture time of one material on a rig (thesis 4.1.1 and 10.2.2)."""
    from twin.rig_config import GonioConfig, load_rig

    config = load_rig(rig)
    if isinstance(config, GonioConfig):
        from twin.capture_time import estimate_gonio

        with console.status("solving the kinematics of every direction pair"):
            summary = estimate_gonio(config).as_dict()
    else:
        from twin.dome_geometry import dome_capture_seconds

        total_s = dome_capture_seconds(config)
        summary = {
            "stage_positions": config.rotation_stage_positions,
            "leds": config.led_count,
            "rgb_cameras": len(config.rgb_camera_polar_deg),
            "frames_per_camera": config.rotation_stage_positions * (config.led_count + 1),
            "total_s": round(total_s, 1),
            "total_h": round(total_s / 3600, 2),
        }
    summary = {"rig": config.name, **summary}
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    _print_table(summary, f"capture time: {config.name}", skip=("rig", "band_exposures_s"))


@app.command()
def gallery(
    out: Annotated[Path, typer.Option(help="Folder for the PNGs and gallery.json.")] = Path(
        "out/gallery"
    ),
    pixels: Annotated[int, typer.Option(min=32, help="Rendered frame size (square).")] = 256,
    spp: Annotated[int, typer.Option(min=1, help="Samples per pixel.")] = 64,
    seed: Annotated[int, typer.Option(help="Seed of the sensor noise.")] = 0,
) -> None:
    """Simulate one raw frame of every ground-truth material in every rig, as PNGs."""
    from twin.rig_gallery import run_gallery

    with console.status("rendering every material in every rig"):
        summary = run_gallery(out, pixels=pixels, spp=spp, seed=seed)
    console.print(f"wrote {len(summary['outputs'])} frames to {out}")


@app.command()
def camchar(
    out: Annotated[
        Path, typer.Option(help="Folder for the photo, the curves and summary.json.")
    ] = Path("out/camchar"),
    chart: Annotated[str, typer.Option(help="esser (113 fields) or colorchecker (24).")] = "esser",
    light: Annotated[str, typer.Option(help="daylight, halogen, fluorescent or hmi.")] = "daylight",
    camera: Annotated[
        str, typer.Option(help="A camera of twin.components.RGB_CAMERA_RESPONSES.")
    ] = "Nikon D70",
    glossy: Annotated[bool, typer.Option(help="Glossy coating on the fields.")] = True,
    spot: Annotated[bool, typer.Option(help="Spot light (else a large area light).")] = True,
    occluder: Annotated[bool, typer.Option(help="An occluder casting a soft shadow.")] = False,
    bend: Annotated[float, typer.Option(help="Bend of the chart, in chart widths (0-0.2).")] = 0.0,
    as_json: JsonFlag = False,
) -> None:
    """Characterize a camera from a rendered chart photograph (thesis chapter 9)."""
    from twin.camchar_report import run_camchar
    from twin.camchar_scenes import ChartScenario

    scenario = ChartScenario(
        chart=chart,
        light=light,
        camera=camera,
        glossy=glossy,
        spot=spot,
        occluder=occluder,
        bend=bend,
    )
    with console.status("rendering the chart photograph and estimating the response"):
        summary = run_camchar(scenario, out)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    _print_table(summary, f"camera characterization: {camera}", skip=("scenario", "outputs"))
    console.print(f"wrote {out / 'responses.png'} and {out / 'chart_photo.png'}")


@app.command(name="spectralize-study")
def spectralize_study(
    out: Annotated[Path, typer.Option(help="Folder for study.json and the PNGs.")] = Path(
        "out/spectralize"
    ),
    texels: Annotated[int, typer.Option(min=16, help="Texture size of the twin materials.")] = 96,
    sweeps: Annotated[bool, typer.Option(help="Run the Fig. 7.9 / 7.10 / 7.6 sweeps.")] = True,
    as_json: JsonFlag = False,
) -> None:
    """Chapter 7: spectralization vs. Imai, Hardeberg, Murakami, Dong and A+ on sparse data."""
    from twin.spectralization_study import run_study

    with console.status("rendering twin textures and running the chapter 7 protocols"):
        summary = run_study(out, texels=texels, sweeps=sweeps)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    for case, result in summary["cases"].items():
        _print_table(result["whisk_broom"], f"{case}: whisk-broom mean relative error, %")
    console.print(f"wrote {out / 'study.json'} and the figures in {out}")


@app.command()
def demo(
    out: Annotated[
        Path, typer.Option(help="Folder for stores, PNGs, metrics.json, report.html.")
    ] = Path("out/demo"),
    as_json: JsonFlag = False,
) -> None:
    """The whole pipeline at small size on built-in defaults, with an HTML report: gonio
    calibration and measurement of the colour checker, BTF, evaluation against the truth,
    spectralization, Figure 4.6 validation (about 10 minutes on 2 cores).

    Example: spectwin demo --out out/demo
    """
    from recon.errors import SpectwinInputError
    from twin.demo import run_demo
    from twin.json_output import dumps

    try:
        with console.status("demo") as status:
            metrics = run_demo(out, step=lambda name: status.update(f"demo: {name}"))
    except SpectwinInputError as error:
        console.print(f"[red]error:[/red] {error}")
        raise typer.Exit(code=2) from None
    if as_json:
        typer.echo(dumps(metrics["headline"]))
        return
    _print_table(metrics["headline"], "spectwin demo")
    console.print(f"report: {out / 'report.html'}")


register_gonio(app)
register_dome(app)


if __name__ == "__main__":
    app()
