"""Validation of any measured BTF against a user's photograph of the sample (thesis 4.2, the
set-up of Figure 4.6): ``spectwin validate BTF --photo PHOTO --environment MAP``.

From files only:

- the photograph (a camera raw file, read as its mosaic by superpixels, or a linear 16-bit or
  floating-point TIFF, PNG or OpenEXR; :mod:`recon.chart_photos.images`,
  :mod:`recon.image_spectralization.rgb_image`), reduced by area averaging to at most
  ``pixels`` on its longer side;
- the light at the sample as a lat-long map (:func:`twin.validate.preview_lighting.
  read_environment`: spectral, or RGB upsampled and said so), +z the sample's normal;
- the sample's four corners in the photograph and its field of view (given, or from the file's
  35 mm equivalent focal length), from which the camera's pose follows
  (:mod:`twin.validate.photo_camera`);
- the camera's response: a measured camera by name, a CSV (``spectwin camchar`` writes one), or
  ``srgb-linear`` for a photograph in linear sRGB (rendered through the CIE 1931 observer).

The BTF is rendered on the sample's square seen by that camera, spectrally and in RGB
(:mod:`twin.validate.btf_panels`), in the camera's channels. Photograph and renderings go to CIE
XYZ by one matrix (linear sRGB's, or the camera's least-squares fit on the 24 measured
ColorChecker reflectances under the map's light), the photograph divided by its exposure (a
given factor, or the one that matches its luminance over the sample to the spectral
rendering's, least squares), and are compared over the central part of the square
(:mod:`twin.validate.panels`). No twin material is needed: the BTF store alone.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import colour
import numpy as np

from recon.btf.store import BTFStore
from recon.chart_photos.charts import colorchecker_reflectances
from recon.chart_photos.images import RAW_SUFFIXES, read_photo
from recon.errors import InputError
from recon.image_files import Encoding
from recon.image_spectralization import camera_response, read_linear_rgb
from recon.rgb_upsampling import reduce_image
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID, cie_illuminant
from twin.materials import load_material
from twin.output_format import dumps
from twin.render.plugins.btf_bsdf import store_table
from twin.render.plugins.spectral_envmap import SpectralMap
from twin.validate.btf_panels import ResponsesOn, render_btf_in_channels, render_btf_spectral
from twin.validate.btf_preview import extrapolated_directions
from twin.validate.figure46 import (
    CIE_RGB_FROM_XYZ,
    cie_rgb_on,
    cmfs_on,
    diffuse_white,
    field_interiors,
    sample_interior,
)
from twin.validate.panels import compare_panels, write_panels
from twin.validate.photo_camera import PhotoCamera, recover_camera
from twin.validate.preview_lighting import RGB_MAP_NOTE, map_lighting, read_environment
from twin.validate.render_back import measured_as
from twin.validate.sphere_probe import MirrorSphere, unwrap_sphere_photo

__all__ = ["SRGB_LINEAR", "PhotoInputs", "read_photo_inputs", "validate_photo"]

SRGB_LINEAR = "srgb-linear"
"""The ``--camera`` of a photograph in linear sRGB."""

_SIZE_M = 0.1
"""Side of the rendered square: under a distant light only the camera's pose relative to the
square's size matters, not the size."""

_MAX_REPROJECTION_PX = 3.0


@dataclass(frozen=True)
class PhotoInputs:
    """A user's photograph and what goes with it, read and checked.

    ``photograph``: ``(H, W, 3)`` linear values at the rendered size; ``camera``: its camera
    at that size; ``reprojection_px``: the corners' reprojection error in the given photograph's
    pixels; ``environment``: the map and ``environment_note`` what became of an RGB one;
    ``response``: the camera's ``(3, K)`` response, ``None`` for linear sRGB; ``notes``: what
    was done to the photograph's values.
    """

    photograph: np.ndarray
    camera: PhotoCamera
    reprojection_px: float
    environment: SpectralMap
    environment_note: str | None
    response: SampledSpectra | None
    notes: tuple[str, ...]


def _corners(values: np.ndarray, width: int, height: int) -> np.ndarray:
    corners = np.asarray(values, np.float64)
    if corners.shape != (4, 2) or not np.all(np.isfinite(corners)):
        raise InputError(
            f"--sample-corners: {corners.size} numbers; expected 8 finite ones: x,y of the "
            "sample's top left, top right, bottom right and bottom left corners"
        )
    outside = (corners < 0).any(axis=1) | (corners[:, 0] > width) | (corners[:, 1] > height)
    if outside.any():
        first = corners[np.argmax(outside)]
        raise InputError(
            f"--sample-corners: corner ({first[0]:g}, {first[1]:g}) lies outside the "
            f"{width} x {height} photograph; expected pixel coordinates inside it"
        )
    return corners


def _exif_fov_deg(path: Path, width: int, height: int) -> float | None:
    """The horizontal field of view from the file's 35 mm equivalent focal length (EXIF),
    or ``None``."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            focal_35mm = image.getexif().get_ifd(0x8769).get(0xA405)
    except (UnidentifiedImageError, OSError, ValueError):
        return None
    if not focal_35mm:
        return None
    focal_px = float(focal_35mm) * np.hypot(width, height) / np.hypot(36.0, 24.0)
    return float(np.degrees(2 * np.arctan(width / 2 / focal_px)))


def _read_photograph(path: Path, encoding: Encoding | None) -> tuple[np.ndarray, int, list[str]]:
    """``(rgb, factor, notes)``: linear RGB of the photograph, the factor its pixels are larger
    than the file's (2 for a raw mosaic's superpixels, else 1) and what was done to it."""
    if path.suffix.lower() in RAW_SUFFIXES:
        photo = read_photo(path, encoding=encoding)
        rgb, factor = photo.rgb()
        return rgb, factor, [note for note in (photo.note, "2 x 2 superpixels") if note]
    linear = read_linear_rgb(path, encoding=encoding)
    return linear.values, 1, [linear.note] if linear.note else []


def _sphere_map(
    sphere: MirrorSphere,
    pose: PhotoCamera,
    response: SampledSpectra | None,
    encoding: Encoding | None,
    map_height: int,
) -> SpectralMap:
    """The light at the sample from the mirror sphere's photograph, taken by ``pose``'s camera
    (:mod:`twin.validate.sphere_probe`); a camera's values go to linear sRGB by its XYZ matrix
    under CIE D65."""
    path = Path(sphere.path)
    if not path.is_file():
        raise InputError(f"--mirror-sphere {path}: no such file")
    rgb, factor, _ = _read_photograph(path, encoding)
    if (rgb.shape[1] * factor, rgb.shape[0] * factor) != (pose.width, pose.height):
        raise InputError(
            f"--mirror-sphere {path}: {rgb.shape[1] * factor} x {rgb.shape[0] * factor} pixels; "
            f"expected the photograph's {pose.width} x {pose.height}, taken by the same camera"
        )
    to_srgb = np.eye(3)
    if response is not None:
        d65 = cie_illuminant("D65", DEFAULT_GRID).values
        xyz = _camera_to_xyz(_response_on(response), d65, DEFAULT_GRID)
        to_srgb = np.linalg.inv(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ) @ xyz
    camera = replace(pose, width=rgb.shape[1], height=rgb.shape[0], focal_px=pose.focal_px / factor)
    x, y, radius = (value / factor for value in sphere.circle)
    return unwrap_sphere_photo(rgb, (x, y, radius), camera, to_srgb, height=map_height)


def read_photo_inputs(
    photo: str | Path,
    environment: str | Path | MirrorSphere,
    corners: np.ndarray,
    *,
    camera: str = SRGB_LINEAR,
    fov_deg: float | None = None,
    pixels: int = 128,
    encoding: Encoding | None = None,
    map_height: int = 64,
) -> PhotoInputs:
    """Read and check the files of a photo validation (module docstring).

    Parameters
    ----------
    photo
        The photograph.
    environment
        The lat-long map of the light at the sample, or a mirror sphere's photograph taken by
        the same camera from the same place (:mod:`twin.validate.sphere_probe`).
    corners
        ``(4, 2)`` x, y of the sample's corners in the photograph's pixels, in the order of the
        BTF's texture (:mod:`twin.validate.photo_camera`).
    camera
        The camera's response: a name, a CSV, or ``"srgb-linear"``.
    fov_deg
        The photograph's horizontal field of view; ``None``: from its EXIF data.
    pixels
        The longer side of the rendered images, at most.
    encoding
        Of an 8-bit photograph: ``"srgb"`` or ``"linear"``.
    map_height
        Rows of the map unwrapped from a mirror sphere (twice as many columns).

    Returns
    -------
    PhotoInputs
    """
    path = Path(photo)
    if not path.is_file():
        raise InputError(f"--photo {path}: no such file")
    if path.suffix.lower() in RAW_SUFFIXES and camera == SRGB_LINEAR:
        raise InputError(
            f"--photo {path}: a camera raw file holds the camera's own RGB; expected --camera "
            "with its response (a name or a spectwin camchar CSV)"
        )
    full, factor, notes = _read_photograph(path, encoding)
    height, width = full.shape[0] * factor, full.shape[1] * factor
    where = _corners(corners, width, height)
    if fov_deg is None:
        fov_deg = _exif_fov_deg(path, width, height)
        if fov_deg is None:
            raise InputError(
                f"--photo {path}: no 35 mm equivalent focal length in its EXIF data; expected "
                "--fov-deg, the photograph's horizontal field of view"
            )
    if not 1.0 <= fov_deg <= 150.0:
        raise InputError(f"--fov-deg: {fov_deg:g}; expected 1 to 150 degrees")
    focal_px = width / 2 / np.tan(np.radians(fov_deg) / 2)
    pose, reprojection = recover_camera(where, _SIZE_M, width, height, focal_px)
    if reprojection > _MAX_REPROJECTION_PX:
        raise InputError(
            f"--sample-corners: a square seen with a {fov_deg:g} degree field of view misses "
            f"them by {reprojection:.1f} px; expected a square sample's corners (check their "
            "order and --fov-deg)"
        )
    reduction = max(1, int(np.ceil(max(full.shape[:2]) / pixels)))
    crop = [size % reduction for size in full.shape[:2]]
    kept = full[
        crop[0] // 2 : full.shape[0] - (crop[0] - crop[0] // 2),
        crop[1] // 2 : full.shape[1] - (crop[1] - crop[1] // 2),
    ]
    reduced, _ = reduce_image(kept, pixels)
    rendered = replace(
        pose,
        width=reduced.shape[1],
        height=reduced.shape[0],
        focal_px=pose.focal_px / (factor * reduction),
    )
    response = None if camera == SRGB_LINEAR else camera_response(camera)
    if isinstance(environment, MirrorSphere):
        spectral_map = _sphere_map(environment, pose, response, encoding, map_height)
        note: str | None = f"unwrapped from a mirror sphere; {RGB_MAP_NOTE}"
    else:
        spectral_map, note = read_environment(environment)
    return PhotoInputs(reduced, rendered, reprojection, spectral_map, note, response, tuple(notes))


@dataclass(frozen=True)
class _Channels:
    """The channels of the two renderings and the matrices taking them and the photograph to
    XYZ: for linear sRGB, the spectral rendering through the CIE 1931 observer and the RGB
    rendering in CIE 1931 RGB (as the twin's Figure 4.6); for a camera, both in its own
    channels."""

    film_on: ResponsesOn
    rgb_on: ResponsesOn
    film_to_xyz: np.ndarray
    rgb_to_xyz: np.ndarray
    photo_to_xyz: np.ndarray


def _channels(inputs: PhotoInputs) -> _Channels:
    response = inputs.response
    if response is None:
        return _Channels(
            lambda grid: cmfs_on(grid).T,
            cie_rgb_on,
            np.eye(3),
            np.linalg.inv(CIE_RGB_FROM_XYZ),
            colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ,
        )

    on = _response_on(response)
    grid = inputs.environment.grid
    light = diffuse_white(inputs.environment, np.eye(grid.size) / np.diff(grid.wavelengths_nm)[0])
    matrix = _camera_to_xyz(on, light, grid)
    return _Channels(on, on, matrix, matrix, matrix)


def _response_on(response: SampledSpectra) -> ResponsesOn:
    def on(grid: WavelengthGrid) -> np.ndarray:
        return resample(response, grid, out_of_range="zero").values

    return on


def _camera_to_xyz(on: ResponsesOn, light: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
    """``(3, 3)`` the camera's values to XYZ: least squares over the 24 measured ColorChecker
    reflectances under ``light`` ``(K,)`` on ``grid``."""
    reflectances = resample(colorchecker_reflectances(), grid, out_of_range="clamp").values
    stimuli = reflectances * light
    return np.linalg.lstsq(stimuli @ on(grid).T, stimuli @ cmfs_on(grid), rcond=None)[0].T


def _chart_fields(material_name: str, camera: PhotoCamera) -> dict[str, np.ndarray]:
    """The field interiors and glossiness of the twin's chart the store names, where it names
    one and every field is in view: compared as the twin's Figure 4.6 compares them (per pixel
    over the matte fields' interiors, and per field)."""
    try:
        material = load_material(material_name)
    except InputError:
        return {}
    fields = field_interiors(material, camera, _SIZE_M)
    if not len(fields) or not fields.any(axis=(1, 2)).all():
        return {}
    glossy = [p.roughness is not None for p in material.parts if p.name.startswith("field_")]
    return {"fields": fields, "glossy": np.array(glossy)}


def validate_photo(
    btf_path: str | Path,
    inputs: PhotoInputs,
    out: str | Path,
    *,
    compressed: bool = False,
    spp: int = 64,
    exposure: float | None = None,
    step: Callable[[str], None] = lambda name: None,
) -> dict[str, Any]:
    """Render the BTF where the photograph was taken and compare (module docstring); writes
    ``validation.png`` and ``metrics.json`` into ``out`` and returns the metrics.

    Parameters
    ----------
    btf_path
        A complete BTF store.
    inputs
        The photograph and its set-up (:func:`read_photo_inputs`).
    out
        A new or empty folder.
    compressed
        Render the store's PCA form (``spectwin compress``) instead of its pairs.
    spp
        Samples per pixel of the renderings.
    exposure
        The photograph's value of a unit of the renderings' (its exposure relative to the map);
        ``None``: fitted over the sample.
    step
        Called with the name of each stage as it starts (progress display).
    """
    if exposure is not None and not exposure > 0:  # before the renders, not after them
        raise InputError(
            f"--exposure: {exposure:g}; expected a positive factor (the photograph's value of a "
            "unit of the renderings')"
        )
    btf = BTFStore.open(btf_path)
    if compressed and not btf.has_compressed:
        raise InputError(f"{btf_path}: no compressed form stored; run spectwin compress first")
    table = store_table(btf, compressed=compressed, lobes=not compressed)
    paths = _channels(inputs)
    channels = SampledSpectra(FINE_GRID, paths.film_on(FINE_GRID), ("R", "G", "B"))
    camera = inputs.camera
    timings = {}
    step("spectral rendering")
    start = time.perf_counter()
    spectral = render_btf_spectral(camera, table, inputs.environment, _SIZE_M, channels, spp=spp)
    timings["spectral_s"] = round(time.perf_counter() - start, 1)
    step("RGB rendering")
    start = time.perf_counter()
    rgb = render_btf_in_channels(camera, table, inputs.environment, _SIZE_M, paths.rgb_on, spp=spp)
    timings["rgb_s"] = round(time.perf_counter() - start, 1)
    spectral_xyz, rgb_xyz = spectral @ paths.film_to_xyz.T, rgb @ paths.rgb_to_xyz.T
    photograph_xyz = inputs.photograph @ paths.photo_to_xyz.T
    chart = _chart_fields(btf.material, camera)
    mask, region = sample_interior(camera, _SIZE_M), "sample"
    if chart:  # as the twin's Figure 4.6: the matte fields' interiors
        mask, region = chart["fields"][~chart["glossy"]].any(axis=0), "matte fields"
    if mask.sum() < 4:
        raise InputError(
            f"--pixels: the sample covers {int(mask.sum())} rendered pixels; expected a larger "
            "--pixels or a photograph where the sample is larger"
        )
    lighting = map_lighting(inputs.environment, "the environment")
    extrapolated = extrapolated_directions(table, lighting, camera.sample_surface(mask))
    fitted = exposure is None
    if exposure is None:
        photo_y, render_y = photograph_xyz[mask][:, 1], spectral_xyz[mask][:, 1]
        exposure = float(photo_y @ render_y / (render_y @ render_y))
    if not exposure > 0:
        raise InputError(
            f"the fitted exposure is {exposure:g}; expected a positive factor (the photograph "
            "is dark where the sample's rendering is bright: check --sample-corners)"
        )
    white = paths.film_to_xyz @ diffuse_white(
        inputs.environment, paths.film_on(inputs.environment.grid)
    )
    panels = compare_panels(
        photograph_xyz / exposure, spectral_xyz, rgb_xyz, white, mask, region, **chart
    )
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_panels(panels, out / "validation.png")
    metrics = {
        "btf": str(btf_path),
        "material": btf.material,
        "form": "pca" if compressed else "raw",
        "measured_as": measured_as(btf),
        "camera": "linear sRGB" if inputs.response is None else "camera response",
        "photograph_notes": list(inputs.notes),
        "environment_note": inputs.environment_note,
        "rendered_size": [camera.width, camera.height],
        "camera_position_in_sample_sides": [
            round(float(v), 3) for v in camera.position_m / _SIZE_M
        ],
        "corners_reprojection_px": round(inputs.reprojection_px, 2),
        "extrapolated": extrapolated,
        "exposure": round(exposure, 6),
        "exposure_fitted": fitted,
        "spp": spp,
        "validation": panels.summary(),
        "timings": timings,
        "figure": str(out / "validation.png"),
    }
    (out / "metrics.json").write_text(dumps(metrics))
    return metrics
