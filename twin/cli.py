"""The ``spectwin`` command line (typer). Commands that compute figures have ``--json``."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

app = typer.Typer(
    help="spectwin: a simulation-first digital twin of spectral reflectance capture rigs.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()


@app.command()
def info(as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table.")) -> None:
    """Show the Mitsuba variant spectwin uses, the LLVM it found and the thread count."""
    from twin.variant import activate

    report = activate().as_dict()
    if as_json:
        typer.echo(json.dumps(report, indent=2))
        return
    table = Table("setting", "value", title="spectwin renderer")
    for key, value in report.items():
        table.add_row(key, str(value))
    console.print(table)


@app.command()
def smoke(
    out: Path = typer.Option(Path("out/smoke"), help="Folder for the EXR, PNGs and summary.json."),
    pixels_per_patch: int = typer.Option(24, min=4, help="Pixels per chart patch (square)."),
    spp: int = typer.Option(256, min=1, help="Samples per pixel."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Render a ColorChecker under the QTH lamp through the LCTF bands; compare with the closed form."""
    from twin.smoke import run_smoke

    with console.status("rendering the smoke scene"):
        summary = run_smoke(out, pixels_per_patch=pixels_per_patch, spp=spp)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    console.print(
        f"[bold]smoke render[/bold] {summary['image_px'][1]}x{summary['image_px'][0]} px, "
        f"{summary['bands']} bands, {summary['spp']} spp, variant {summary['variant']['variant']}, "
        f"{summary['render_s']:.2f} s"
    )
    console.print(
        f"largest relative band error vs closed form: {100 * summary['max_abs_relative_error']:.2f} %"
    )
    console.print(f"wrote {', '.join(str(out / name) for name in summary['outputs'])}")


if __name__ == "__main__":
    app()
