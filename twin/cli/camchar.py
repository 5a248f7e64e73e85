"""``spectwin camchar`` and its studies: a camera's spectral response from chart photographs
(thesis chapter 9).

- ``camchar PHOTO...``: real photographs (camera raw, linear 16-bit TIFF or PNG) of a chart
  under known lights (``recon.chart_photos``, written by ``twin.studies.camchar_photos``);
- ``camchar-study``: a rendered chart photograph of a built-in camera (``twin.studies.camchar``);
- ``camchar-cameras``: the 51 measured cameras, each left out of its prior
  (``twin.studies.camchar_cameras``).
"""

from __future__ import annotations

import time
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import numpy as np
import typer

from twin.cli.choices import Chart, Encoding, EncodingOption, Light, RGBCamera
from twin.cli.errors import fail, require_output_folder
from twin.cli.output import JsonFlag, console, print_summary
from twin.cli.points import parse_corners

if TYPE_CHECKING:
    from recon.chart_photos.charts import Chart as ChartModel
    from recon.chart_photos.images import LinearPhoto

__all__ = ["register"]


class Bayer(StrEnum):
    """Bayer patterns of ``recon.chart_photos.images.BAYER_PATTERNS``."""

    rggb = "rggb"
    bggr = "bggr"
    grbg = "grbg"
    gbrg = "gbrg"


def _per_photo(values: list, count: int, option: str, *, optional: bool) -> list:
    """``values`` of an option given once for every photograph or once per photograph (or, if
    ``optional``, not at all: None for every photograph)."""
    if not values and optional:
        return [None] * count
    if len(values) == count:
        return list(values)
    if len(values) == 1:
        return values * count
    fail(
        f"{option}: given {len(values)} times for {count} photographs; expected once for all or "
        "once per photograph"
    )


def _chart(chart: str, layout: str | None) -> ChartModel:
    from recon.chart_photos.charts import CHARTS, chart_from_csv, named_chart

    if chart in CHARTS:
        named = named_chart(chart)
        if layout is not None and layout != f"{named.rows}x{named.columns}":
            fail(f"--layout {layout}: the {chart} is {named.rows}x{named.columns}")
        return named
    if not chart.lower().endswith(".csv"):
        fail(f"--chart {chart}: expected one of {sorted(CHARTS)} or a CSV file of reflectances")
    if layout is None:
        fail(f"--chart {chart}: a CSV of reflectances needs --layout ROWSxCOLUMNS, e.g. 4x6")
    rows, _, columns = layout.lower().partition("x")
    if not (rows.isdigit() and columns.isdigit()):
        fail(f"--layout {layout!r}: expected ROWSxCOLUMNS, e.g. 4x6")
    return chart_from_csv(chart, int(rows), int(columns))


def characterize(
    photos: Annotated[
        list[Path],
        typer.Argument(
            help="Photographs of the chart: camera raw files (DNG, CR2, NEF, ARW, ...) or linear "
            "16-bit TIFF/PNG, one channel (a raw mosaic, with --bayer) or RGB.",
            show_default=False,
        ),
    ],
    light: Annotated[
        list[str] | None,
        typer.Option(
            help="The light: a CIE illuminant (D65, A, FL11, ...), tungsten_lab, "
            "fluorescent_office, or FILE.csv[:COLUMN] of its spectrum. Once for all photographs "
            "or once per photograph; photographs under the same light are exposures of one "
            "scene and are merged.",
            show_default=False,
        ),
    ] = None,
    chart: Annotated[
        str,
        typer.Option(
            help="colorchecker (ColorChecker Classic 24, shipped reflectances) or FILE.csv of "
            "the patches' reflectances in reading order (with --layout)."
        ),
    ] = "colorchecker",
    layout: Annotated[
        str | None, typer.Option(help="Rows x columns of a CSV chart, e.g. 4x6.")
    ] = None,
    corners: Annotated[
        list[str] | None,
        typer.Option(
            help="The chart's outer corners 'x,y;x,y;x,y;x,y' in pixels, the first at the first "
            "patch, then along its row, around the chart. Once for all photographs or once per "
            "photograph; if not given, colour-checker-detection looks for a ColorChecker.",
            show_default=False,
        ),
    ] = None,
    exposure_s: Annotated[
        list[float] | None,
        typer.Option(
            "--exposure-s",
            help="Exposure time in seconds, once for all photographs or once per photograph; "
            "needed only to merge several exposures under one light.",
            show_default=False,
        ),
    ] = None,
    bayer: Annotated[
        Bayer | None, typer.Option(help="Bayer pattern of single-channel TIFF/PNG mosaics.")
    ] = None,
    encoding: EncodingOption = None,
    black_level: Annotated[
        float | None,
        typer.Option(min=0.0, help="Black level of TIFF/PNG values (default 0; raw: the file's)."),
    ] = None,
    white_level: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Clipping level (default: the format's largest value; raw: the file's).",
        ),
    ] = None,
    truth: Annotated[
        Path | None,
        typer.Option(
            help="A measured response to compare with: curves (CSV wavelength_nm,R,G,B) or the "
            "white balance under each light (CSV light,R,G,B, a row per --light)."
        ),
    ] = None,
    prior: Annotated[
        bool,
        typer.Option(
            help="The prior learned from the 51 measured cameras shipped with spectwin "
            "(--no-prior: the thesis's extended estimator alone)."
        ),
    ] = True,
    out: Annotated[
        Path, typer.Option(help="Folder for response.csv, patches.csv, response.png, summary.json.")
    ] = Path("out/camchar"),
    as_json: JsonFlag = False,
) -> None:
    """Characterize a camera from photographs of a chart under known lights (thesis chapter 9):
    its relative spectral response R, G, B, the fit's residuals per patch and, with --truth, the
    error against a measured response.

    Example: spectwin camchar IMG_1.CR2 --light D65 --corners '410,300;2980,310;2990,2010;400,2000'
    """
    from recon.chart_photos.characterize import (
        ChartPhotograph,
        characterize_photographs,
        estimation_grid,
    )
    from recon.chart_photos.lights import light_spectrum
    from recon.chart_photos.truth import check_truth, read_truth
    from twin.studies.camchar_photos import write_characterization

    started = time.perf_counter()
    require_output_folder(out)
    if not light:
        fail("--light: expected the light of the photographs (once, or once per photograph)")
    count = len(photos)
    lights = _per_photo(light, count, "--light", optional=False)
    times = _per_photo(exposure_s or [], count, "--exposure-s", optional=True)
    given_corners = _per_photo(corners or [], count, "--corners", optional=True)
    chart_model = _chart(chart, layout)
    spectra = {spec: light_spectrum(spec) for spec in dict.fromkeys(lights)}
    grid = estimation_grid(chart_model, spectra)
    measured = None
    if truth is not None:
        measured = read_truth(truth)
        check_truth(measured, grid, list(spectra))
    if not given_corners[0] and chart_model.name != "colorchecker":
        fail(
            "--corners: expected the chart's corners; colour-checker-detection finds only the "
            "ColorChecker Classic"
        )
    photographs = []
    with console.status("reading the photographs"):
        for path, spec, seconds, text in zip(photos, lights, times, given_corners, strict=True):
            photo = _read(path, bayer, encoding, black_level, white_level)
            found = parse_corners(text, "--corners") if text else _detect(photo)
            photographs.append(
                ChartPhotograph(photo, spec, 1.0 if seconds is None else seconds, found)
            )
    with console.status("estimating the response"):
        result = characterize_photographs(
            photographs, chart_model, spectra, prior="measured" if prior else None
        )
    notes = sorted({p.photo.note for p in photographs if p.photo.note})
    inputs = {
        "photographs": [str(path) for path in photos],
        "chart": chart_model.name,
        "chart_note": chart_model.note,
        "photo_notes": notes,
        "lights": list(result.lights),
        "corners": {str(p.photo.source): p.corners.round(1).tolist() for p in photographs},
        "prior": "51 measured cameras" if prior else "none",
    }
    summary = write_characterization(
        result,
        out,
        inputs=inputs,
        truth=measured,
        seconds=time.perf_counter() - started,
    )
    shown = ["residual_rms_pct", "residual_max_pct", "residual_max_at", "peak_nm", "seconds"]
    shown += [key for key in summary if key.startswith("truth_") and key.endswith("worst_pct")]
    print_summary(
        summary if as_json else {key: summary[key] for key in shown},
        f"camera characterization: {count} photographs, {len(result.lights)} lights",
        as_json,
    )
    if not as_json:
        for note in notes + ([chart_model.note] if chart_model.note else []):
            console.print(f"note: {note}")
        console.print(f"wrote {', '.join(str(out / name) for name in summary['outputs'])}")


def _read(
    path: Path,
    bayer: Bayer | None,
    encoding: Encoding | None,
    black_level: float | None,
    white_level: float | None,
) -> LinearPhoto:
    from recon.chart_photos.images import read_photo

    return read_photo(
        path,
        bayer=None if bayer is None else bayer.value,
        encoding=None if encoding is None else encoding.value,
        black_level=black_level,
        white_level=white_level,
    )


def _detect(photo: LinearPhoto) -> np.ndarray:
    from recon.chart_photos.detect import detect_colorchecker

    return detect_colorchecker(photo)


def study(
    out: Annotated[
        Path, typer.Option(help="Folder for the photo, the curves and summary.json.")
    ] = Path("out/camchar-study"),
    chart: Annotated[Chart, typer.Option(help="esser: 113 fields; colorchecker: 24.")] = (
        Chart.esser
    ),
    light: Annotated[Light, typer.Option(help="The light of the photograph.")] = Light.daylight,
    camera: Annotated[RGBCamera, typer.Option(help="The camera to characterize.")] = (
        RGBCamera.nikon_d70
    ),
    glossy: Annotated[bool, typer.Option(help="Glossy coating on the fields.")] = True,
    spot: Annotated[bool, typer.Option(help="Spot light (else a large area light).")] = True,
    occluder: Annotated[bool, typer.Option(help="An occluder casting a soft shadow.")] = False,
    bend: Annotated[
        float, typer.Option(min=0.0, max=0.2, help="Bend of the chart, in chart widths.")
    ] = 0.0,
    as_json: JsonFlag = False,
) -> None:
    """Characterize a built-in camera from a rendered chart photograph (thesis chapter 9): the
    thesis's basic and extended estimators against the camera's true response."""
    from twin.studies.camchar import run_camchar
    from twin.studies.camchar_scenes import ChartScenario

    require_output_folder(out)
    scenario = ChartScenario(
        chart=chart.value,
        light=light.value,
        camera=camera.value,
        glossy=glossy,
        spot=spot,
        occluder=occluder,
        bend=bend,
    )
    with console.status("rendering the chart photograph and estimating the response"):
        summary = run_camchar(scenario, out)
    print_summary(
        summary,
        f"camera characterization: {camera.value}",
        as_json,
        skip=("scenario", "outputs"),
    )
    if not as_json:
        console.print(f"wrote {out / 'responses.png'} and {out / 'chart_photo.png'}")


def cameras(
    out: Annotated[
        Path, typer.Option(help="Folder for table.csv, errors.png, worst_camera.png, summary.json.")
    ] = Path("out/camchar-cameras"),
    camera: Annotated[
        list[str] | None,
        typer.Option(
            help="A measured camera to characterize, e.g. 'Nikon D850' (repeat for several; "
            "default: all 51). Its prior is always learned from all the others."
        ),
    ] = None,
    seed: Annotated[
        int, typer.Option(min=0, help="Seed of the specularity, shading and noise.")
    ] = 0,
    as_json: JsonFlag = False,
) -> None:
    """Chapter 9 on 51 measured cameras, each left out: the extended estimator with a prior
    learned from the other cameras, without it, and Jiang et al. 2013 on the same photographs."""
    from twin.studies.camchar_cameras import run_camchar_cameras

    require_output_folder(out)
    summary = run_camchar_cameras(out, cameras=camera, seed=seed, progress=not as_json)
    if as_json:
        print_summary(summary, "camera characterization across cameras", as_json)
        return
    rows = {}
    for method, statistics in summary["methods"].items():
        rows[f"{method}_mean_pct"] = statistics["mean_pct"]
        rows[f"{method}_max_pct"] = statistics["max_pct"]
        rows[f"{method}_hardest"] = ", ".join(statistics["hardest"])
    print_summary(rows, f"worst channel's RMSE over {summary['cameras']} cameras (seed {seed})")
    console.print(f"wrote {out / 'table.csv'}, {out / 'errors.png'} and {out / 'worst_camera.png'}")


def register(app: typer.Typer) -> None:
    """Add ``camchar``, ``camchar-study`` and ``camchar-cameras`` to ``app``."""
    app.command(name="camchar")(characterize)
    app.command(name="camchar-study")(study)
    app.command(name="camchar-cameras")(cameras)
