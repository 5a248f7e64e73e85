"""Validation of a measured BTF by rendering it back (thesis 4.2): ``spectwin validate``.

For a BTF store of the twin's colour checker (raw, or its PCA form with ``compressed``):

- Figure 4.6 (:mod:`twin.validate.figure46`): photograph of the true material in the room, spectral
  and
  RGB renderings of the BTF under the room's captured spectral map, Delta E94 maps;
- the spectrophotometer comparison of Fig. 4.3/4.4 (:mod:`twin.validate.spectrophotometer`): a 45/0
  instrument on the true material versus the BTF integrated over theta_i = 45 degrees, in the
  BTF's bands (a dome BTF's are the dome's spectral camera's).

Writes ``figure46.png``, ``spectrophotometer_45_0.png`` and ``metrics.json`` into ``out``; the
metrics say whether the BTF was measured spectrally or in RGB (:mod:`recon.btf.rgb_import`) and
how its RGB became the rendered spectra. The raw form is rendered with a specular lobe fitted
per texel (:mod:`recon.btf.specular_lobe`), which holds the highlights of glossy fields that the
direction sampling only touches; the compressed form without.

The same store and settings give the same figures and metrics to the last digit, whatever
Dr.Jit's thread count: every render has a fixed seed (a light group its own,
:func:`twin.render.light_groups.group_seed`) and scenes load the same way every time
(:mod:`twin.render.render`; ``tests/twin/validate/test_validate_reproducible.py``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import colour
import numpy as np

from recon.btf.rgb_import import rgb_source
from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.image_spectralization import write_rgb_exr
from recon.spectral_exr import write_spectral_exr
from twin.materials import load_material
from twin.output_format import dumps
from twin.render.plugins.btf_bsdf import store_table
from twin.validate.figure46 import (
    Figure46,
    field_interiors,
    photograph_camera,
    render_figure46,
)
from twin.validate.panels import write_panels
from twin.validate.photo_camera import square_corners
from twin.validate.spectrophotometer import compare_45_0, field_spots, write_45_0_figure

__all__ = ["MIN_PIXELS", "measured_as", "validate_btf"]

MIN_PIXELS = 23
"""Smallest image size at which every field of the colour checker keeps an interior pixel (and
the Delta E94 of every field is a number); larger sizes all do."""


def measured_as(btf: BTFStore) -> str:
    """How a BTF store's spectra were measured, in words.

    Parameters
    ----------
    btf
        A BTF store.

    Returns
    -------
    str
        ``"spectral"``, RGB upsampled (by which method), or RGB spectralized from spot spectra or
        a 45/0 reading.
    """
    source = rgb_source(btf)
    if source is None:
        return "spectral"
    layout = source.layout
    described = source.colour_space + ("" if layout == "image folder" else f", {layout}")
    if source.spectralized is not None:
        spots = source.spectralized
        return f"RGB ({described}) spectralized from {spots.describe()} (Eq. 6.10)"
    return f"RGB ({described}), rendered spectrally after {source.upsampling}"


def validate_btf(
    btf_path: str | Path,
    out: str | Path,
    *,
    compressed: bool = False,
    pixels: int = 96,
    spp: int = 256,
    map_height: int = 64,
    map_spp: int = 64,
    passbands: Callable[[Any], Any] | None = None,
    step: Callable[[str], None] = lambda name: None,
) -> dict[str, Any]:
    """Render Figure 4.6 and the 45/0 comparison for the BTF at ``btf_path`` into ``out``.

    Parameters
    ----------
    btf_path
        A BTF store whose ``material`` attribute names a twin material with chart fields.
    out
        Folder for the PNGs and ``metrics.json`` (created).
    compressed
        Render the store's ``pca/`` form (``spectwin compress``) instead of its raw pairs.
    pixels, spp
        Image size and samples per pixel of the three panels. At 64 spp the path-tracing noise
        of the photograph and the renderings dominates per-pixel Delta E94. On the twin's true
        BTF of the colour checker at 13 x 13 directions (rings 0, 30, 60 degrees as lights and
        views, the 156 pairs the rig reaches, 64 texels, band-weighted like the instrument),
        ``benchmarks/figure46.py`` prints for the matte fields' interiors: per pixel 2.43
        (spectral) vs 3.21 (RGB) at 128 px and 64 spp, 1.23 vs 2.77 at 96 px and 256 spp; per
        field mean 0.85 vs 2.77 and 0.61 vs 2.71 (with specular lobes; the same to the last
        digit on every run).
    map_height, map_spp
        Rows of the captured lat-long map (twice as many columns) and the samples per pixel of
        the mirror sphere's image it is unwrapped from.
    passbands
        ``passbands(wavelengths_nm)``: the passbands the BTF's bands stand for in the 45/0
        comparison (the rig's, :attr:`twin.kinds.registry.RigKind.passbands`); ``None``: narrow
        bands.
    step
        Called with the name of each stage as it starts (progress display).

    Returns
    -------
    dict
        The metrics written to ``metrics.json``.
    """
    sizes = {"pixels": pixels, "spp": spp, "map_height": map_height, "map_spp": map_spp}
    for name, value in sizes.items():
        if isinstance(value, bool) or not isinstance(value, int) or value < 4:
            raise InputError(f"{name}: expected an integer of at least 4, got {value!r}")
    btf = BTFStore.open(btf_path)
    try:
        material = load_material(btf.material)
    except InputError:
        raise InputError(
            f"{btf_path}: material {btf.material!r} is not one of the twin's; expected --photo "
            "and --environment: your photograph of the sample and the light where it was taken"
        ) from None
    chart = any(part.name.startswith("field_") for part in material.parts)
    if compressed and not btf.has_compressed:
        raise InputError(f"{btf_path}: no compressed form stored; run spectwin compress first")
    if not compressed and not btf.written().any():
        raise InputError(
            f"{btf_path}: no direction pair is written yet; finish the BTF with spectwin "
            "process --resume"
        )
    if chart and not field_spots(material, btf.texels[0]).any(axis=(1, 2)).all():
        raise InputError(
            f"{btf_path}: its {btf.texels[0]} texels leave chart fields without a texel in the "
            "45/0 measuring spot; process the capture with --texels 16 or more"
        )
    field_pixels = field_interiors(material, photograph_camera(pixels)).sum(axis=(1, 2))
    if chart and not field_pixels.all():
        raise InputError(
            f"pixels: {pixels} px leave chart fields of {btf.material!r} without an interior "
            f"pixel to compare; expected at least {MIN_PIXELS}"
        )
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    table = store_table(btf, compressed=compressed, lobes=not compressed)
    timings: dict[str, float] = {}
    figures = {"figure46": str(out / "figure46.png")}

    step("Figure 4.6: map capture and three renderings")
    start = time.perf_counter()
    figure = render_figure46(
        material,
        table,
        pixels=pixels,
        spp=spp,
        map_size=(map_height, 2 * map_height),
        map_spp=map_spp,
    )
    write_panels(figure.panels, out / "figure46.png")
    photo_inputs = write_photo_inputs(figure, material.size_m, pixels, out)
    timings["figure46_s"] = round(time.perf_counter() - start, 1)
    metrics: dict[str, Any] = {
        "btf": str(btf_path),
        "material": btf.material,
        "form": "pca" if compressed else "raw",
        "measured_as": measured_as(btf),
        "bytes_rendered_from": int(table.nbytes),
        "specular_lobe_texels_fraction": round(
            table.lobes.glossy_fraction if table.lobes is not None else 0.0, 4
        ),
        "settings": {
            "pixels": pixels,
            "spp": spp,
            "map_size": [map_height, 2 * map_height],
            "map_spp": map_spp,
        },
        "figure46": figure.panels.summary(),
        "photo_inputs": photo_inputs,
        "figures": figures,
    }
    if chart:
        fields = [part.name for part in material.parts if part.name.startswith("field_")]
        field_spectral, field_rgb = figure.panels.field_delta_e()
        metrics["figure46_per_field_delta_e94"] = {
            name: {"spectral": round(float(s), 3), "rgb": round(float(r), 3)}
            for name, s, r in zip(fields, field_spectral, field_rgb, strict=True)
        }
        step("45/0 spectrophotometer comparison")
        start = time.perf_counter()
        bands = None if passbands is None else passbands(btf.grid.wavelengths_nm)
        forty_five = compare_45_0(table, material, spp=spp, passbands=bands)
        write_45_0_figure(forty_five, btf.grid.wavelengths_nm, out / "spectrophotometer_45_0.png")
        timings["spectrophotometer_s"] = round(time.perf_counter() - start, 1)
        metrics["spectrophotometer_45_0"] = forty_five.summary()
        figures["spectrophotometer_45_0"] = str(out / "spectrophotometer_45_0.png")
    metrics["timings"] = timings
    (out / "metrics.json").write_text(dumps(metrics))
    return metrics


def write_photo_inputs(figure: Figure46, size_m: float, pixels: int, out: Path) -> dict[str, Any]:
    """Write the photograph (linear sRGB OpenEXR) and the captured map (spectral OpenEXR) into
    ``out`` with what ``spectwin validate --photo`` needs besides: the sample's corners in the
    photograph and its field of view. Returns those, with the two files."""
    camera = photograph_camera(pixels)
    srgb = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    write_rgb_exr(out / "photograph.exr", figure.panels.photograph @ srgb.T)
    environment = figure.environment
    write_spectral_exr(
        out / "environment.exr", environment.radiance.astype(np.float32), environment.grid
    )
    corners = camera.project(square_corners(size_m))
    return {
        "photo": str(out / "photograph.exr"),
        "environment": str(out / "environment.exr"),
        "sample_corners": ";".join(f"{x:.3f},{y:.3f}" for x, y in corners),
        "fov_deg": round(camera.fov_deg, 4),
        "camera": "srgb-linear",
    }
