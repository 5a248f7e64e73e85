"""``spectwin btf export`` and ``spectwin btf import``: a BTF store as spectral OpenEXR slices
(one per direction pair, Fichet et al. 2021 layout) with a JSON direction index, and back
(:mod:`recon.btf.exchange`); RGB BTFs from images with a direction table
(:mod:`recon.btf.rgb_import`); ``spectwin btf render``: a preview of any BTF store in a standard
scene (:mod:`twin.validate.btf_preview`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from twin.cli.errors import SpectwinGroup, fail, remove_if_interrupted, require_output_folder
from twin.cli.output import JsonFlag, print_summary
from twin.cli.store import require_sound_btf

if TYPE_CHECKING:
    from recon.btf.reading_spectralization import MeasuringSpot

__all__ = ["register"]

btf_app = typer.Typer(
    cls=SpectwinGroup,
    help="Exchange BTF stores as spectral OpenEXR slices with a JSON direction index; import "
    "RGB BTFs from images; render a preview of a BTF store.",
    no_args_is_help=True,
)


@btf_app.command("export")
def export(
    ctx: typer.Context,
    store: Annotated[Path, typer.Argument(help="A complete BTF store (.btf.zarr).")],
    out: Annotated[Path, typer.Option(help="New or empty folder for the slices.")],
    as_json: JsonFlag = False,
) -> None:
    """Write one spectral EXR per direction pair (pair_00000.exr, ...; float32, T.<nm>nm
    channels) and directions.json (light and view direction per file, wavelengths, texture size,
    the store's attributes), the index last.

    Example: spectwin btf export out/demo/colour_checker.btf.zarr --out out/slices
    """
    from recon.btf.exchange import export_btf
    from recon.btf.store import BTFStore

    require_output_folder(out)
    require_sound_btf(store, "export")
    btf = BTFStore.open(store)
    remove_if_interrupted(ctx, out)
    index = export_btf(btf, out, progress=not as_json)
    summary = {
        "pairs": btf.n_pairs,
        "texels": "x".join(str(v) for v in btf.texels),
        "bands": btf.grid.size,
        "index": str(index),
    }
    print_summary(summary, f"exported {btf.material}", as_json)


@btf_app.command("import")
def import_(
    ctx: typer.Context,
    source: Annotated[
        Path,
        typer.Argument(
            help="A folder of spectral EXR slices with directions.json, or of RGB images with "
            "directions.csv; a UBO2003/ATRIUM .zip or a UBO2014 .btf."
        ),
    ],
    out: Annotated[Path, typer.Option(help="The new BTF store (.btf.zarr); must not exist.")],
    upsampling: Annotated[
        str, typer.Option(help="RGB images: how RGB becomes spectra (jakob2019).")
    ] = "jakob2019",
    scale: Annotated[
        float, typer.Option(min=1e-6, help="RGB images: reflectance factor of a linear value 1.")
    ] = 1.0,
    material: Annotated[
        str | None,
        typer.Option(help="RGB images: the material's name (colorchecker16: validate compares)."),
    ] = None,
    texels: Annotated[
        int | None,
        typer.Option(min=1, help="RGB images: largest side of the stored texture (area average)."),
    ] = None,
    spectra: Annotated[
        Path | None,
        typer.Option(
            help="RGB images: spot spectra, a CSV pair,x,y,<nm>,... (pair index in the "
            "directions' order, texel column and row of the stored texture, then the spectrum "
            "as a reflectance factor); or one spectrophotometer reading at 45/0, a CSV "
            "wavelength_nm,reflectance (the mean over its measuring spot at the BTF's pair "
            "nearest light at 45, view at 0 degrees, within 15): the BTF is spectralized from "
            "them, not upsampled.",
            show_default=False,
        ),
    ] = None,
    response: Annotated[
        str | None,
        typer.Option(
            help="With --spectra: the camera's response, a shipped camera by name (e.g. "
            "'Nikon D850') or a CSV wavelength_nm,R,G,B.",
            show_default=False,
        ),
    ] = None,
    measuring_spot: Annotated[
        str | None,
        typer.Option(
            help="With a 45/0 reading: its measuring spot, X,Y,WIDTH,HEIGHT in texels of the "
            "stored texture (default: the whole texture).",
            show_default=False,
        ),
    ] = None,
    gains_only: Annotated[
        bool,
        typer.Option(
            "--gains-only",
            help="With spots: fit the camera term as a gain per channel (not the response "
            "times a smooth factor per channel).",
        ),
    ] = False,
    free_highlights: Annotated[
        bool,
        typer.Option(
            "--free-highlights",
            help="With spots: fit the regression prior's base freely (not holding a flat "
            "reflectance, the interface reflection of a dielectric, to itself).",
        ),
    ] = False,
    as_json: JsonFlag = False,
) -> None:
    """Read spectral EXR slices and their direction index (as spectwin btf export writes them),
    or an RGB BTF (sRGB images, one per direction pair, with directions.csv: file,
    light_theta_deg, light_phi_deg, view_theta_deg, view_phi_deg; or a Bonn database UBO2003 or
    ATRIUM archive or UBO2014 file), upsampled to spectra and flagged as RGB, into a new BTF
    store; the store is complete once every image is in. With --spectra and --response the
    RGB BTF is spectralized from spot spectra (thesis section 10.1, Eq. 6.10) or from one
    45/0 reading of the sample (Eq. 6.9: the mean over its measuring spot) and flagged so.

    Example: spectwin btf import out/slices --out out/copy.btf.zarr
    Example: spectwin btf import UBO_CORDUROY256.zip --out corduroy.btf.zarr --texels 64
    Example: spectwin btf import images --spectra spots.csv --response 'Nikon D850' --out s.btf.zarr
    Example: spectwin btf import images --spectra reading.csv --response 'Nikon D850' --out r.zarr
    """
    from recon.btf.exchange import INDEX_NAME, import_exr_slices
    from recon.btf.rgb_import import DIRECTION_TABLE, import_rgb_images, is_rgb_source, rgb_source
    from recon.image_spectralization.camera_fit import MAX_DEGREE

    require_output_folder(out)
    if out.exists():
        fail(f"--out {out}: exists; expected a new BTF store path (nothing was overwritten)")
    remove_if_interrupted(ctx, out)
    rgb = is_rgb_source(source) and not (source / INDEX_NAME).is_file()
    if (spectra is None) != (response is None):
        fail("--spectra, --response: expected both (spot spectra and the camera) or neither")
    if spectra is not None and scale != 1.0:
        fail("--scale: not with --spectra (a spectralized import takes its scale from the spots)")
    if (gains_only or free_highlights) and spectra is None:
        fail("--gains-only, --free-highlights: only with --spectra (spot spectra)")
    spot = None if measuring_spot is None else _measuring_spot(measuring_spot)
    if rgb:
        btf = import_rgb_images(
            source,
            out,
            upsampling=upsampling,
            scale=scale,
            material=material,
            texels=texels,
            spectra=spectra,
            response=response,
            measuring_spot=spot,
            camera_degree=0 if gains_only else MAX_DEGREE,
            neutral=not free_highlights,
            progress=not as_json,
        )
    else:
        given = [
            name
            for name, value in (
                ("--material", material),
                ("--scale", scale != 1.0),
                ("--texels", texels),
                ("--spectra", spectra),
                ("--measuring-spot", measuring_spot),
                ("--gains-only", gains_only),
                ("--free-highlights", free_highlights),
            )
            if value
        ]
        if given:
            fail(
                f"{', '.join(given)}: only for RGB images (a folder with {DIRECTION_TABLE}, a "
                ".zip or a .btf)"
            )
        btf = import_exr_slices(source, out, progress=not as_json)
    summary = {
        "pairs": btf.n_pairs,
        "texels": "x".join(str(v) for v in btf.texels),
        "bands": btf.grid.size,
        "material": btf.material,
        "store": str(out),
        "complete": btf.complete,
    }
    if rgb:
        recorded = rgb_source(btf)
        spots = recorded.spectralized if recorded is not None else None
        summary["from_rgb"] = (
            f"sRGB, upsampled by {upsampling}"
            if spots is None
            else f"camera RGB, spectralized from {spots.describe()} ({spots.design})"
        )
        summary["format"] = recorded.layout if recorded is not None else None
    print_summary(summary, "imported BTF", as_json)


def _measuring_spot(text: str) -> MeasuringSpot:
    """``--measuring-spot X,Y,WIDTH,HEIGHT`` as whole texels."""
    from recon.btf.reading_spectralization import MeasuringSpot

    try:
        values = [int(cell) for cell in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 4:
        fail(f"--measuring-spot {text!r}: expected X,Y,WIDTH,HEIGHT, four whole texels")
    return MeasuringSpot(*values)


@btf_app.command("render")
def render(
    ctx: typer.Context,
    store: Annotated[Path, typer.Argument(help="A complete BTF store (.btf.zarr).")],
    out: Annotated[
        Path, typer.Option(help="New or empty folder for render.exr, render.png, render.json.")
    ],
    preset: Annotated[
        str | None,
        typer.Option(help="The light: studio (halogen area lights) or daylight (D65 sky, sun)."),
    ] = None,
    environment: Annotated[
        Path | None,
        typer.Option(
            help="The light: a lat-long OpenEXR map (2:1), spectral or RGB (upsampled).",
            show_default=False,
        ),
    ] = None,
    shape: Annotated[
        str,
        typer.Option(
            help="plane (tilted towards the camera), sphere (UV-mapped) or cloth (hanging over "
            "a rod in soft folds, the texture repeated in 4 cm tiles)."
        ),
    ] = "plane",
    pixels: Annotated[int, typer.Option(help="Image size (square).")] = 256,
    spp: Annotated[
        int, typer.Option(help="Samples per pixel (rendered: the next power of 4).")
    ] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Render a preview of the BTF (its PCA form where the store has one) on a plane, a
    sphere or a cloth, spectrally where the BTF is, lit by a preset (studio by default) or an
    environment map: render.exr (spectral OpenEXR, one channel per band), render.png (sRGB) and
    render.json (settings, time, the BTF's form, the light and view directions beyond those the
    BTF sampled). A BTF on a sphere is a preview: the sample's square is stretched round it; on
    the cloth it is repeated in tiles.

    Example: spectwin btf render out/lego.btf.zarr --out out/lego_preview --preset daylight
    Example: spectwin btf render corduroy.btf.zarr --out prev --environment room.exr --shape sphere
    Example: spectwin btf render corduroy.btf.zarr --out drape --shape cloth
    """
    from twin.validate.btf_preview import SHAPES, render_btf_preview
    from twin.validate.preview_lighting import PRESETS, environment_lighting

    require_output_folder(out)
    if out.is_dir() and any(out.iterdir()):
        fail(f"--out {out}: not empty; expected a new or empty folder (nothing was overwritten)")
    if preset is not None and environment is not None:
        fail("--preset, --environment: expected one light, a preset or an environment map")
    if preset is not None and preset not in PRESETS:
        fail(f"--preset: expected one of {', '.join(PRESETS)}, got {preset!r}")
    if shape not in SHAPES:
        fail(f"--shape: expected one of {', '.join(SHAPES)}, got {shape!r}")
    for name, value in (("--pixels", pixels), ("--spp", spp)):
        if value < 1:
            fail(f"{name}: expected a positive integer, got {value}")
    require_sound_btf(store, "render", allow_unregistered=True, compressed=True)
    lighting = (
        environment_lighting(environment)
        if environment is not None
        else PRESETS[preset or "studio"]()
    )
    remove_if_interrupted(ctx, out)
    summary = render_btf_preview(
        store,
        out,
        lighting,
        shape=shape,  # checked against SHAPES above
        pixels=pixels,
        spp=spp,
        progress=not as_json,
    )
    if as_json:
        print_summary(summary, "", as_json)
        return
    extrapolated = "; ".join(summary["extrapolated"]) or "none"
    note = f" ({summary['environment_note']})" if summary["environment_note"] else ""
    typer.echo(
        f"rendered {summary['material']} ({summary['form']}, {summary['measured_as']}) on a "
        f"{shape} in {summary['lighting']}{note}: {pixels} x {pixels} px, {spp} spp, "
        f"{summary['render_s']:.1f} s; extrapolated: {extrapolated}; written to {out}"
    )


def register(app: typer.Typer) -> None:
    """Add the ``btf`` command group to ``app``."""
    app.add_typer(btf_app, name="btf")
