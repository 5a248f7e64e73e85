"""A preview of any BTF store in a standard scene (``spectwin btf render``).

The BTF (gonioreflectometer, dome or imported; its PCA form where the store has one, else its
pairs decoded with the specular lobes fitted per texel, as ``spectwin validate`` renders them:
:func:`twin.render.plugins.btf_bsdf.store_table`) is put on a plane tilted towards the camera,
on a sphere or on a cloth hanging over a grey rod (:mod:`twin.validate.preview_geometry`,
:mod:`twin.validate.preview_cloth`) and lit by a preset or an environment map
(:mod:`twin.validate.preview_lighting`). A BTF sample on a sphere is a preview only: the
measured square is wrapped round it by the sphere's UV mapping, stretched along the equator and
pinched at the poles. On the cloth it is repeated in tiles of 4 cm, unstretched, its seams
visible where the texture does not tile.

The image is rendered spectrally (Mitsuba's path tracer, at most 4 bounces, below its Russian
roulette, so that two BTFs are rendered with the same random numbers: the BSDF samples the cosine
hemisphere whatever its values), one film channel per band of the BTF: a triangle of unit area
around the band centre reaching the neighbouring centres, so a channel is the radiance
(W m^-2 sr^-1 nm^-1 for the lights' relative scale) at its band. The samples are split in
passes (a progress bar), pass ``i`` seeded by :func:`twin.render.light_groups.group_seed` of
the seed and ``i``: the same store and settings give the same image.

Written to the output folder: ``render.exr`` (spectral OpenEXR, Fichet et al. 2021),
``render.png`` (sRGB, white balanced to the light, the 99th percentile of luminance at 1:
:func:`recon.preview.spectral_to_srgb`) and ``render.json`` last (the settings, the render
time, the BTF's form and the directions the scene asks of the BTF beyond those it sampled).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.preview import spectral_to_srgb
from recon.progress import progress_steps
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from recon.spectral_exr import write_spectral_exr
from twin.components.lamps import FINE_GRID
from twin.materials.surfaces import texture_coordinates
from twin.output_format import dumps
from twin.render.light_groups import group_seed, render_lit
from twin.render.plugins.btf_bsdf import BTFTable, CompressedTable, btf_bsdf, store_table
from twin.render.render import load_scene
from twin.render.shapes import mesh_shape
from twin.render.spectra import rendered_spp
from twin.render.transforms import rotate, scale
from twin.validate.preview_cloth import ROD_HEIGHT_M, ROD_RADIUS_M, cloth_mesh
from twin.validate.preview_geometry import (
    PLANE_TILT_DEG,
    SAMPLE_SIZE_M,
    SPHERE_RADIUS_M,
    Shape,
    SurfaceView,
    beyond_fraction,
    polar_deg,
    preview_camera,
    surface_view,
)
from twin.validate.preview_lighting import PreviewLighting
from twin.validate.render_back import measured_as

__all__ = ["SHAPES", "band_channels", "extrapolated_directions", "render_btf_preview"]

SHAPES: tuple[Shape, ...] = ("plane", "sphere", "cloth")
MAX_DEPTH = 4
_ROD_LENGTH_M = 0.15
"""The cloth's rod (grey, reflectance 0.3), its ends beyond the cloth's edges."""
_TOLERANCE_DEG = 0.5
_MAX_SKY_POINTS = 2000


def band_channels(grid: WavelengthGrid) -> SampledSpectra:
    """One film channel per band of ``grid`` on the lamps' fine grid: a triangle of unit area
    from the previous band centre to the next (10 nm either side for a single band)."""
    centres = grid.wavelengths_nm
    steps = np.diff(centres)
    below = np.concatenate([[steps[0] if steps.size else 10.0], steps])
    above = np.concatenate([steps, [steps[-1] if steps.size else 10.0]])
    fine = FINE_GRID.wavelengths_nm
    rows = []
    for centre, low, high in zip(centres, below, above, strict=True):
        rows.append(np.interp(fine, [centre - low, centre, centre + high], [0.0, 1.0, 0.0]))
    values = np.array(rows)
    values /= np.trapezoid(values, fine, axis=1)[:, None]
    names = tuple(f"band_{index:03d}" for index in range(grid.size))
    return SampledSpectra(FINE_GRID, values, names)


def _sample_entries(shape: Shape, table: BTFTable | CompressedTable) -> dict[str, object]:
    """The sample's scene entries: the shape with the BTF (and the cloth's rod)."""
    bsdf = btf_bsdf(table)
    if shape == "sphere":
        return {"sample": {"type": "sphere", "radius": SPHERE_RADIUS_M, "bsdf": bsdf}}
    if shape == "cloth":
        mesh = cloth_mesh()
        ends = [[sign * _ROD_LENGTH_M / 2, 0.0, ROD_HEIGHT_M] for sign in (-1, 1)]
        rod = {
            "type": "cylinder",
            "p0": ends[0],
            "p1": ends[1],
            "radius": ROD_RADIUS_M - 0.001,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.3}},
        }
        uv = texture_coordinates(mesh)
        sample = mesh_shape("sample", mesh, load_scene(bsdf), uv=uv, normals=True)
        return {"sample": sample, "rod": rod}
    return {
        "sample": {
            "type": "rectangle",
            "to_world": rotate([1, 0, 0], PLANE_TILT_DEG) @ scale(SAMPLE_SIZE_M / 2),
            "bsdf": bsdf,
        }
    }


def _largest_polar_deg(directions: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(np.min(directions[:, 2]), -1.0, 1.0))))


def extrapolated_directions(
    table: BTFTable | CompressedTable, lighting: PreviewLighting, surface: SurfaceView
) -> list[str]:
    """What the scene asks of the BTF beyond the largest polar angles it sampled (of its
    lights, of its views; :mod:`twin.validate.preview_geometry`), one phrase each; empty when
    nothing is.

    Parameters
    ----------
    table
        The BTF as the plugin's table.
    lighting
        The preview's light.
    surface
        The sample's visible pixels, their normals and view directions.

    Returns
    -------
    list of str
        E.g. ``"views beyond 60 deg on 12 % of the sample"``.
    """
    if not surface.mask.any():
        return []
    light_max = _largest_polar_deg(table.light_dirs)
    view_max = _largest_polar_deg(table.view_dirs)
    found = []
    views = polar_deg(surface.normals, surface.views) > view_max + _TOLERANCE_DEG
    if views.any():
        found.append(f"views beyond {view_max:.0f} deg on {100 * views.mean():.0f} % of the sample")
    towards = {name: position - surface.points for name, position in lighting.lamps.items()} | {
        name: np.broadcast_to(direction, surface.points.shape)
        for name, direction in lighting.sun.items()
    }
    for name, vectors in towards.items():
        directions = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
        angles = polar_deg(surface.normals, directions)
        lit = angles < 90.0
        beyond = lit & (angles > light_max + _TOLERANCE_DEG)
        if beyond.any():
            share = 100 * beyond.sum() / lit.sum()
            found.append(f"{name} beyond {light_max:.0f} deg on {share:.0f} % of the lit sample")
    if lighting.sky is not None:
        step = max(1, len(surface.normals) // _MAX_SKY_POINTS)
        fraction = beyond_fraction(
            surface.normals[::step], *lighting.sky, light_max + _TOLERANCE_DEG
        )
        if fraction > 0.005:
            found.append(
                f"{100 * fraction:.0f} % of the sky's light from beyond {light_max:.0f} deg"
            )
    return found


def _form(btf: BTFStore, table: BTFTable | CompressedTable) -> str:
    if isinstance(table, CompressedTable):
        compressed = table.compressed
        return (
            f"PCA ({compressed.brightness_scores.shape[1]} brightness, "
            f"{compressed.n_spectral} spectral components, {compressed.layout})"
        )
    lobes = table.lobes is not None and bool(table.lobes.weight.any())
    return "decoded" + (" with specular lobes" if lobes else "")


def _write_png(path: Path, image: np.ndarray) -> None:
    from skimage import io

    handle, temporary = tempfile.mkstemp(suffix=".png", dir=path.parent)
    os.close(handle)
    try:
        io.imsave(temporary, image, check_contrast=False)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def render_btf_preview(
    btf_path: str | Path,
    out: str | Path,
    lighting: PreviewLighting,
    *,
    shape: Shape = "plane",
    pixels: int = 256,
    spp: int = 64,
    seed: int = 0,
    progress: bool = False,
) -> dict[str, Any]:
    """Render the BTF store at ``btf_path`` in a preview scene into ``out`` (module docstring).

    Parameters
    ----------
    btf_path
        A complete BTF store.
    out
        A new or empty folder for ``render.exr``, ``render.png`` and ``render.json``.
    lighting
        The light (:mod:`twin.validate.preview_lighting`).
    shape
        ``"plane"``, ``"sphere"`` or ``"cloth"``.
    pixels
        Image size (square).
    spp
        Samples per pixel (rendered as Mitsuba's ``ldsampler`` takes them: the next power of 4).
    seed
        Seed of the render.
    progress
        Show a progress bar on standard error.

    Returns
    -------
    dict
        What ``render.json`` holds.
    """
    if shape not in SHAPES:
        raise InputError(f"--shape: expected one of {', '.join(SHAPES)}, got {shape!r}")
    for name, value in (("--pixels", pixels), ("--spp", spp)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise InputError(f"{name}: expected a positive integer, got {value!r}")
    btf = BTFStore.open(btf_path)
    compressed = btf.has_compressed
    table = store_table(btf, compressed=compressed, lobes=not compressed)
    grid = table.grid
    channels = band_channels(grid)
    camera = preview_camera(pixels)
    entries = {**lighting.entries, **_sample_entries(shape, table)}

    total = rendered_spp(spp)
    passes = 4 if total >= 16 else 1
    start = time.perf_counter()
    image = np.zeros((pixels, pixels, grid.size))
    with progress_steps("rendering", passes, enabled=progress) as advance:
        for index in range(passes):
            image += render_lit(
                camera,
                channels,
                entries,
                lighting.groups,
                spp=total // passes,
                seed=group_seed(seed, index),
                max_depth=MAX_DEPTH,
            )
            advance()
    image /= passes
    render_s = time.perf_counter() - start

    surface = surface_view(shape, pixels)
    sample_mean = image[surface.mask].mean(axis=0) if surface.mask.any() else np.zeros(grid.size)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    white = resample(lighting.white, grid, out_of_range="clamp")
    write_spectral_exr(
        out / "render.exr",
        image.astype(np.float32),
        grid,
        attributes={"spectwin": f"btf render of {Path(btf_path).name}"},
    )
    _write_png(out / "render.png", spectral_to_srgb(image, grid, white=white))
    summary: dict[str, Any] = {
        "btf": str(btf_path),
        "material": btf.material,
        "measured_as": measured_as(btf),
        "form": _form(btf, table),
        "lighting": lighting.description,
        "environment_note": lighting.note,
        "shape": shape,
        "pixels": pixels,
        "spp": spp,
        "rendered_spp": total,
        "seed": seed,
        "render_s": round(render_s, 2),
        "bands": grid.size,
        "sample_pixels": int(surface.mask.sum()),
        "sample_mean_radiance": float(sample_mean.mean()),
        "extrapolated": extrapolated_directions(table, lighting, surface),
        "files": {name: str(out / name) for name in ("render.exr", "render.png", "render.json")},
    }
    (out / "render.json").write_text(dumps(summary))
    return summary
