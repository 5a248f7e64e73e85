"""``spectwin twin-vs-real BENCH``: predict a real capture frame by frame with the twin of its
bench, then compare with the real frames (:mod:`twin.studies.twin_vs_real`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from twin.cli.errors import require_output_folder
from twin.cli.output import JsonFlag, SeedOption, console, print_summary

__all__ = ["register"]


def twin_vs_real(
    bench: Annotated[
        str,
        typer.Argument(
            help="A bench of scenes/benches by name (llanos2019) or the path of a bench YAML file.",
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            help="Folder for report.json, patches.csv and the figures "
            "(predicted_vs_measured.png, residual_map.png, dark.png, frame.png).",
        ),
    ] = Path("out/twin-vs-real"),
    band: Annotated[
        list[int] | None,
        typer.Option(help="Only the frames of this filter band in nm (repeat for several)."),
    ] = None,
    spp: Annotated[
        int, typer.Option(min=4, max=4096, help="Samples per pixel of the renders.")
    ] = 64,
    seed: SeedOption = 0,
    as_json: JsonFlag = False,
) -> None:
    """Predict every frame of a real bench capture with the twin, then compare.

    The twin fits the lamp (its power per filter and, where the bench file asks, its position)
    on the bench's fit patches at one exposure per filter, and the dark signal on the fit
    exposures' dark frames; everything else is predicted before it is compared. The report
    gives the error of the predicted patch means per channel, the clipping, the dark frames and
    the split between fitted and evaluated frames. About two minutes for llanos2019 on 2 cores.

    Example: spectwin twin-vs-real llanos2019 --out out/llanos
    """
    from twin.studies.twin_vs_real import run_twin_vs_real

    require_output_folder(out)
    report = run_twin_vs_real(
        bench, out, spp=spp, seed=seed, bands_nm=tuple(band or ()), progress=not as_json
    )
    if as_json:
        print_summary(report, "twin against reality", as_json)
        return
    console.print(f"[bold]{report['bench']}[/bold] ({report['camera']}), {report['frames']} frames")
    console.print(f"fitted on: {report['split']['fitted_on']}")
    console.print(f"evaluated on: {report['split']['evaluated_on']}")
    print_summary(report["fitted"], "fitted parameters")
    errors = Table(
        "patches",
        "n",
        "median",
        "95th percentile",
        title="|predicted - measured| / measured of the patch means "
        f"(unclipped, >= {report['split']['min_dn']:g} DN)",
    )
    for name, row in report["mean_error"].items():
        label = {"all": "evaluated, all channels", "colour_patches": "colour patches"}.get(
            name, f"evaluated, {name}" if len(name) == 1 else name
        )
        errors.add_row(
            label, str(row["n"]), f"{100 * row['median']:.1f} %", f"{100 * row['p95']:.1f} %"
        )
    console.print(errors)
    print_summary(
        report["clipping"], "clipping (a patch channel with >= 1 % of its pixels at the top)"
    )
    dark = Table(
        "exposure",
        "role",
        "mean (DN)",
        "spatial spread (DN)",
        "temporal spread (DN)",
        title="dark frames, measured / predicted",
    )
    for row in report["dark"]:
        dark.add_row(
            f"{row['exposure_ms']:g} ms",
            row["role"],
            f"{row['measured_mean_dn']:.2g} / {row['predicted_mean_dn']:.2g}",
            f"{row['measured_spread_dn']:.2g} / {row['predicted_spread_dn']:.2g}",
            f"{row['measured_temporal_dn']:.2g} / {row['predicted_temporal_dn']:.2g}",
        )
    console.print(dark)
    goals = report["goals"]
    verdict = ", ".join(
        f"{name} {'met' if goals[f'{name}_met'] else 'missed'}"
        for name in ("median", "p95", "clipping")
    )
    console.print(f"goals (median <= 5 %, p95 <= 12 %, clipping >= 95 %): {verdict}")
    console.print(f"wrote {out / 'report.json'}, {out / 'patches.csv'} and the figures in {out}")


def register(app: typer.Typer) -> None:
    """Add the ``twin-vs-real`` command to ``app``."""
    app.command(name="twin-vs-real")(twin_vs_real)
