"""The thesis's Figure 4.6 validation: photograph, spectral rendering and RGB rendering of a
measured BTF in a room lit by halogen spots and fluorescent tubes (thesis 4.2).

- The room: grey walls, two small halogen spots (disks of 3 cm radius aimed at the sample, the
  lab tungsten spectrum of ``recon/data/spectra/lights``) and two long fluorescent tubes (the
  office fluorescent spectrum there); the sample lies at the origin, facing +z. Spots and tubes
  are rendered as two light groups with their spectra in the film (:mod:`twin.render.light_groups`),
  which keeps the fluorescent lines from adding Monte Carlo noise to the colours.
- Its illumination is captured as a lat-long spectral map with a mirror sphere at the sample's
  position (:mod:`twin.validate.envmap_capture`).
- (a) "Photograph": the true material (its geometry and part spectra) rendered in the room and
  recorded by a colorimetric RGB camera (CIE 1931 colour matching functions, so that the panel
  differences come from the data, not from the camera's own metamerism).
- (b) Spectral rendering: a square with the measured BTF (:mod:`twin.render.plugins.btf_bsdf`)
  under the
  captured spectral map, recorded through the same colour matching functions.
- (c) RGB rendering: BTF and map converted to CIE 1931 RGB first (reflectance under equal
  energy, a perfect white = 1; radiance by the matching functions), one rendering per channel.

All three are compared (:mod:`twin.validate.panels`) in CIE L*a*b* relative to the white point
of the map (one white balance), Delta E94 per pixel over the interiors of the chart's matte
fields, and of every field's mean colour (matte and glossy reported apart); on a material
without chart fields, per pixel over the central :data:`SAMPLE_INTERIOR` of the sample's square.
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from recon.measured_data import read_spectra_csv
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID
from twin.materials import Material
from twin.render.light_groups import LightGroup, render_lit
from twin.render.plugins.btf_bsdf import BTFTable, CompressedTable
from twin.render.plugins.spectral_envmap import SpectralMap
from twin.render.scene import PinholeCamera
from twin.render.shapes import mitsuba_shape
from twin.render.spectra import irregular_spectrum
from twin.render.transforms import look_at, rotate, scale, translate
from twin.validate.btf_panels import PANEL_SEED, render_btf_in_channels, render_btf_spectral
from twin.validate.envmap_capture import capture_mirror_sphere
from twin.validate.panels import Panels, compare_panels, polygon_mask
from twin.validate.photo_camera import PhotoCamera, square_corners

__all__ = [
    "CIE_RGB_FROM_XYZ",
    "SAMPLE_INTERIOR",
    "Figure46",
    "cie_rgb_on",
    "cmfs_on",
    "diffuse_white",
    "field_interiors",
    "photograph_camera",
    "render_figure46",
    "render_spectral_panel",
    "room_entries",
    "room_lights",
    "sample_interior",
]

_OBSERVER = "CIE 1931 2 Degree Standard Observer"
_CAMERA_POSITION_M = np.array([0.0, -0.22, 0.16])
CIE_RGB_FROM_XYZ = colour.RGB_COLOURSPACES["CIE RGB"].matrix_XYZ_to_RGB
"""XYZ to CIE 1931 RGB, the primaries of the RGB rendering."""
SAMPLE_INTERIOR = 0.8
"""Fraction of the sample's side compared on a material without chart fields: its edges, where
the flat BTF square and a material's relief differ by parallax, are left out."""


def _lamp_spectrum(name: str, scale: float) -> SampledSpectra:
    """A lamp spectrum of ``recon/data/spectra/lights`` on ``FINE_GRID``, peak ``scale``."""
    spectrum = read_spectra_csv(f"spectra/lights/{name}.csv")
    on_grid = resample(spectrum, FINE_GRID, out_of_range="clamp").values[0]
    return SampledSpectra(FINE_GRID, scale * on_grid / on_grid.max())


def _diffuse(value: float) -> dict[str, object]:
    return {
        "type": "diffuse",
        "reflectance": irregular_spectrum(
            SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, value))
        ),
    }


def _unit_emitter() -> dict[str, object]:
    return {
        "type": "area",
        "radiance": irregular_spectrum(SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size))),
    }


def room_entries() -> dict[str, object]:
    """Mitsuba scene entries of the room's walls (grey, reflectance 0.5); the sample position is
    the origin, facing +z."""
    return {
        "room": {
            "type": "cube",
            "to_world": translate([0.0, 0.0, 0.7]) @ scale([2.0, 2.0, 1.5]),
            "flip_normals": True,
            "bsdf": _diffuse(0.5),
        }
    }


def room_lights(
    *, spot_radiance: float = 4000.0, tube_radiance: float = 60.0
) -> tuple[LightGroup, LightGroup]:
    """The room's lamps as two light groups (:mod:`twin.render.light_groups`): two small halogen
    spots
    (lab tungsten) and two long fluorescent tubes (office fluorescent), peak radiances given.

    The spots are disks facing the sample, not spheres: with sphere emitters, Mitsuba 3.9's path
    tracer (llvm_ad_spectral) gave the spots' light 4.3 % less in the room as soon as the tubes
    were emitters too, however dim (1e-6), and their wall light came out 3.8 % brighter in the
    photograph than through a mirror-sphere capture; with disks both differences are gone
    (0.01 % and within the map's resolution; measured in the session notes).
    """
    spots = {
        f"spot_{index}": {
            "type": "disk",
            "to_world": look_at(origin=position, target=[0.0, 0.0, 0.0], up=[0.0, 0.0, 1.0])
            @ scale(0.03),
            "emitter": _unit_emitter(),
        }
        for index, position in enumerate(([0.9, 0.6, 1.4], [-0.7, 1.0, 1.2]))
    }
    tubes = {
        f"tube_{index}": {
            "type": "rectangle",
            "to_world": translate([x, 0.2, 2.15])
            @ rotate([1, 0, 0], 180)
            @ scale([0.05, 0.8, 1.0]),
            "emitter": _unit_emitter(),
        }
        for index, x in enumerate((-0.6, 0.5))
    }
    return (
        LightGroup("halogen spots", spots, _lamp_spectrum("tungsten_lab", spot_radiance)),
        LightGroup("fluorescent tubes", tubes, _lamp_spectrum("fluorescent_office", tube_radiance)),
    )


def photograph_camera(pixels: int) -> PinholeCamera:
    """The camera of the photograph and of both renderings: square, ``pixels`` across, looking
    at the sample from 27 cm, 36 degrees above its plane."""
    return PinholeCamera(_CAMERA_POSITION_M, 0.055, pixels)


def _xyz_film() -> SampledSpectra:
    return SampledSpectra(FINE_GRID, cmfs_on(FINE_GRID).T, ("X", "Y", "Z"))


def cie_rgb_on(grid: WavelengthGrid) -> np.ndarray:
    """CIE 1931 RGB colour matching functions ``(3, K)`` on ``grid``."""
    return CIE_RGB_FROM_XYZ @ cmfs_on(grid).T


@dataclass(frozen=True)
class Figure46:
    """The comparison of the three panels (:class:`twin.validate.panels.Panels`) and the
    room's map the BTF was rendered under."""

    panels: Panels
    environment: SpectralMap


def field_interiors(
    material: Material, camera: PinholeCamera | PhotoCamera, size_m: float | None = None
) -> np.ndarray:
    """``(n_fields, H, W)`` image masks of the central half of every chart field's top face as
    ``camera`` sees it (the comparison leaves out field edges, where the flat BTF square and the
    raised fields of the true material differ by parallax); ``size_m``: the side the camera's
    world gives the sample (default the material's own)."""
    scale = 1.0 if size_m is None else size_m / material.size_m
    masks = []
    for part in (p for p in material.parts if p.name.startswith("field_")):
        low, high = part.mesh.bounds
        middle, half = (low + high) / 2, 0.25 * (high - low)
        corners = np.array(
            [
                [middle[0] + sx * half[0], middle[1] + sy * half[1], high[2]]
                for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            ]
        )
        masks.append(polygon_mask(camera.project(scale * corners), *_image_size(camera)))
    width, height = _image_size(camera)
    return np.stack(masks) if masks else np.zeros((0, height, width), bool)


def _image_size(camera: PinholeCamera | PhotoCamera) -> tuple[int, int]:
    """``(width, height)`` of ``camera``'s image."""
    if isinstance(camera, PinholeCamera):
        return camera.pixels, camera.pixels
    return camera.width, camera.height


def sample_interior(camera: PinholeCamera | PhotoCamera, size_m: float) -> np.ndarray:
    """``(H, W)`` the pixels of ``camera`` inside the central :data:`SAMPLE_INTERIOR` of the
    sample's square: the region compared on a material without chart fields."""
    corners = camera.project(square_corners(SAMPLE_INTERIOR * size_m))
    return polygon_mask(corners, *_image_size(camera))


def diffuse_white(environment: SpectralMap, responses: np.ndarray) -> np.ndarray:
    """The value of a perfect white diffuser facing +z under ``environment`` (E / pi) in the
    channels ``responses`` ``(n, K)`` on the map's grid."""
    rows = environment.radiance.shape[0]
    directions_cos = np.cos((np.arange(rows) + 0.5) * np.pi / rows)
    weights = environment.solid_angles() * np.maximum(directions_cos, 0)[:, None]
    radiance = np.einsum("hwk,hw->k", environment.radiance, weights) / np.pi
    return responses @ radiance * np.diff(environment.grid.wavelengths_nm)[0]


def render_figure46(
    material: Material,
    table: BTFTable | CompressedTable,
    *,
    pixels: int = 96,
    spp: int = 64,
    map_size: tuple[int, int] = (64, 128),
    map_spp: int = 64,
    map_grid: WavelengthGrid = DEFAULT_GRID,
) -> Figure46:
    """Capture the room's map, render the three panels and compare them (module docstring).

    The mirror sphere is imaged with ``8 * map_size[0]`` pixels across at ``map_spp`` samples
    per pixel (the panels are rendered at ``spp``). A white diffuser lit by the map captured at
    64 spp matches the room within 2 % at 32 x 64 map pixels and 1.4 % at 64 x 128 (the spots'
    true directions within their map pixel; see the session notes).
    """
    room, lights = room_entries(), room_lights()
    environment, _ = capture_mirror_sphere(
        room,
        map_grid,
        groups=lights,
        camera_direction=(0.3, -0.4, 1.0),
        pixels=8 * map_size[0],
        spp=map_spp,
        height=map_size[0],
        width=map_size[1],
    )
    camera = photograph_camera(pixels)
    true_sample = {part.name: mitsuba_shape(part) for part in material.parts}
    photograph = render_lit(
        camera, _xyz_film(), {**room, **true_sample}, lights, spp=spp, seed=PANEL_SEED
    )
    spectral = render_spectral_panel(material, table, environment, pixels=pixels, spp=spp)
    rgb = np.einsum(
        "ij,hwj->hwi",
        np.linalg.inv(CIE_RGB_FROM_XYZ),
        render_btf_in_channels(camera, table, environment, material.size_m, cie_rgb_on, spp=spp),
    )
    white = diffuse_white(environment, cmfs_on(environment.grid).T)
    fields = field_interiors(material, camera)
    if len(fields):
        glossy = np.array(
            [p.roughness is not None for p in material.parts if p.name.startswith("field_")]
        )
        chart = {"fields": fields, "glossy": glossy}
        mask, region = fields[~glossy].any(axis=0), "matte fields"
    else:
        chart, mask, region = {}, sample_interior(camera, material.size_m), "sample"
    panels = compare_panels(photograph, spectral, rgb, white, mask, region, **chart)
    return Figure46(panels, environment)


def render_spectral_panel(
    material: Material,
    table: BTFTable | CompressedTable,
    environment: SpectralMap,
    *,
    pixels: int = 96,
    spp: int = 64,
) -> np.ndarray:
    """Panel (b) alone: the BTF on the material's square under a spectral map, recorded through
    the CIE 1931 matching functions, XYZ ``(pixels, pixels, 3)``
    (:func:`twin.validate.btf_panels.render_btf_spectral`)."""
    return render_btf_spectral(
        photograph_camera(pixels), table, environment, material.size_m, _xyz_film(), spp=spp
    )


def cmfs_on(grid: WavelengthGrid) -> np.ndarray:
    """CIE 1931 colour matching functions ``(K, 3)`` on ``grid``."""
    cmfs = colour.MSDS_CMFS[_OBSERVER]
    return np.stack(
        [np.interp(grid.wavelengths_nm, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)],
        axis=1,
    )
