"""``spectwin spectralize``: a user's linear RGB image and spot spectra to a spectral image
(thesis Eq. 6.10), with the cross-validated error of every spot (Eq. 6.8).

The reconstruction is ``recon.image_spectralization``; the files are written by
``twin.studies.spectralized_image``.
"""

from __future__ import annotations

import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from twin.cli.choices import EncodingOption
from twin.cli.errors import fail, remove_if_interrupted, require_output_folder
from twin.cli.output import JsonFlag, console, print_summary

__all__ = ["register"]

_SHOWN_SPOTS = 24  # more spots: the summary and the worst five


class Appearance(StrEnum):
    """``recon.image_spectralization.APPEARANCES``: chosen, or one space."""

    auto = "auto"
    rgbxy = "rgbxy"
    learned = "learned"


class Interleave(StrEnum):
    """Layouts of ``recon.envi.ENVI_INTERLEAVES``."""

    bsq = "bsq"
    bil = "bil"


def _spot_table(xy: np.ndarray, errors: np.ndarray) -> Table:
    """The spots' held-out errors, one decimal: all of them, or the worst five (spots without
    one, outside a large image's cross-validation window, are left out)."""
    held_out = np.flatnonzero(np.isfinite(errors))
    few = held_out.size <= _SHOWN_SPOTS
    order = held_out if few else held_out[np.argsort(errors[held_out])[-5:][::-1]]
    title = "held-out error per spot" if few else "worst five spots"
    table = Table("x", "y", "error (%)", title=f"{title} (Eq. 6.8, cross-validated)")
    for index in order:
        table.add_row(str(xy[index, 0]), str(xy[index, 1]), f"{errors[index]:.1f}")
    return table


def spectralize(
    ctx: typer.Context,
    image: Annotated[
        Path,
        typer.Argument(
            help="The RGB image: linear 16-bit PNG or TIFF, floating-point TIFF or OpenEXR "
            "(R, G, B channels).",
            show_default=False,
        ),
    ],
    spectra: Annotated[
        Path,
        typer.Option(
            help="Spot spectra: a CSV with the header x,y,<nm>,<nm>,... and one row per spot "
            "(its pixel's column x and row y from 0 at the top left, then its spectrum); with "
            "--mask, the header label,<nm>,... and one row per label.",
            show_default=False,
        ),
    ],
    response: Annotated[
        str,
        typer.Option(
            help="The camera's spectral response: one of the 51 measured cameras shipped with "
            "spectwin by name (e.g. 'Nikon D850') or a CSV wavelength_nm,R,G,B (as spectwin "
            "camchar writes).",
            show_default=False,
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            help="Folder for spectra.exr, spectra.hdr/.raw (ENVI), preview.png and spots.json; "
            "never overwritten."
        ),
    ] = Path("out/spectralized"),
    fast: Annotated[
        bool,
        typer.Option(
            help="The thesis's prior (and its rgbxy space unless --appearance names one) "
            "without cross-validation: one solve (in rgbxy of a lattice of pixels on images of "
            "100 000 pixels or more, see --sample-stride), no per-spot errors (by default both are "
            "chosen by three-fold cross-validation over the spots)."
        ),
    ] = False,
    appearance: Annotated[
        Appearance,
        typer.Option(
            help="Which pixels the prior links: rgbxy (like colour nearby, the thesis's), "
            "learned (like spectra predicted from the patch around each pixel by a map fitted "
            "on the spots) or auto (the one the cross-validation finds better).",
        ),
    ] = Appearance.auto,
    kriging: Annotated[
        bool,
        typer.Option(
            help="Blend in Murakami 2007's kriged estimate from the spots by the weight the "
            "cross-validation finds best (0 where it does not help); --no-kriging: the chosen "
            "prior alone.",
        ),
    ] = True,
    sample_stride: Annotated[
        int | None,
        typer.Option(
            help="In rgbxy on an image of 100 000 pixels or more, solve every Nth pixel of "
            "every Nth row and the spots (in the cross-validation's folds and finally), the "
            "other pixels from their nearest solved ones in appearance space (by default every "
            "second: faster and closer to the truth than every pixel); 1: every pixel.",
            show_default=False,
            min=1,
        ),
    ] = None,
    whole_image_cross_validation: Annotated[
        bool,
        typer.Option(
            "--whole-image-cross-validation",
            help="Cross-validate a large image whole (by default an image of more than "
            "100 000 pixels is cross-validated in a central window of that size at full "
            "resolution, and only its spots get a held-out error).",
        ),
    ] = False,
    mask: Annotated[
        Path | None,
        typer.Option(
            help="A label image (PNG or TIFF, one channel of whole numbers, the RGB image's "
            "size) whose areas of each label are where that label's spectrum was measured "
            "(0: no spot)."
        ),
    ] = None,
    gains_only: Annotated[
        bool,
        typer.Option(
            "--gains-only",
            help="Fit the camera term as a gain per channel (not the response times a smooth "
            "factor per channel).",
        ),
    ] = False,
    encoding: EncodingOption = None,
    radiance: Annotated[
        bool,
        typer.Option(
            help="The spots are radiance (emissive EXR, preview as it is), not reflectance "
            "(reflective EXR, preview under D65)."
        ),
    ] = False,
    interleave: Annotated[
        Interleave, typer.Option(help="Layout of the ENVI raster.")
    ] = Interleave.bsq,
    as_json: JsonFlag = False,
) -> None:
    """Spectralize an RGB image from spectra measured at a few of its pixels (thesis chapter
    6, Eq. 6.10): a spectral OpenEXR and ENVI image, an sRGB preview and every spot's error
    predicted while it was held out (Eq. 6.8).

    Example: spectwin spectralize photo.tif --spectra spots.csv --response Nikon_D850 --out out/p
    """
    from recon.image_spectralization import (
        camera_response,
        read_linear_rgb,
        read_spot_mask,
        read_spots_csv,
        spectralize_image,
    )
    from recon.image_spectralization.camera_fit import MAX_DEGREE
    from recon.image_spectralization.window import CROSS_VALIDATION_PIXELS
    from recon.spectralize.hierarchy import SAMPLE_STRIDE
    from twin.studies.spectralized_image import OUTPUTS, write_spectralized_image

    started = time.perf_counter()
    require_output_folder(out)
    present = [name for name in OUTPUTS if (out / name).exists()]
    if present:
        fail(
            f"--out {out}: already holds {', '.join(present)}; expected a new folder or one "
            "without them (nothing was overwritten)"
        )
    remove_if_interrupted(ctx, out)
    rgb = read_linear_rgb(image, encoding=None if encoding is None else encoding.value)
    if mask is None:
        spots = read_spots_csv(spectra)
    else:
        spots = read_spot_mask(spectra, mask, rgb.values)
    curves = camera_response(response)
    result = spectralize_image(
        rgb.values,
        spots,
        curves,
        fast=fast,
        appearance=appearance.value,
        kriging=kriging,
        camera_degree=0 if gains_only else MAX_DEGREE,
        cross_validation_pixels=None if whole_image_cross_validation else CROSS_VALIDATION_PIXELS,
        sample_stride=SAMPLE_STRIDE if sample_stride is None else sample_stride,
        progress=not as_json,
    )
    inputs = {
        "image": str(image),
        "image_note": rgb.note,
        "spectra": str(spectra),
        "mask": None if mask is None else str(mask),
        "response": response,
    }
    summary = write_spectralized_image(
        result, spots, out, inputs=inputs, radiance=radiance, interleave=interleave.value
    )
    summary["seconds"]["total"] = time.perf_counter() - started
    if as_json:
        print_summary(summary, "spectralization", as_json)
        return
    shown = ["spots", "bands", "appearance", "prior", "prior_chosen_by", "kriging_weight"]
    shown += ["cross_validated_error_pct"]
    shown += [key for key in summary if key.startswith("spot_error_")]
    shown += ["spot_fit_residual_pct"]
    print_summary(
        {key: summary[key] for key in shown} | {"total_s": summary["seconds"]["total"]},
        f"spectralization of {image.name}: {summary['image_px'][1]} x {summary['image_px'][0]} px",
    )
    if result.spot_errors is not None:
        console.print(_spot_table(spots.xy, result.spot_errors))
    else:
        console.print("per-spot errors need the cross-validation, which --fast skips")
    for note in ([rgb.note] if rgb.note else []) + list(result.notes):
        console.print(f"note: {note}")
    console.print(f"wrote {', '.join(str(out / name) for name in OUTPUTS)}")


def register(app: typer.Typer) -> None:
    """Add ``spectralize`` to ``app``."""
    app.command(name="spectralize")(spectralize)
