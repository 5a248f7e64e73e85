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

All three are compared in CIE L*a*b* relative to the white point of the map (one white
balance), Delta E94 per pixel over the interiors of the chart's fields (matte and glossy
reported apart); the PNG shows them with one tone curve.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from recon.measured_data import read_spectra_csv
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID
from twin.materials import Material
from twin.render.light_groups import LightGroup, render_lit
from twin.render.plugins.btf_bsdf import BTFTable, CompressedTable, btf_bsdf
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.scene import PinholeCamera
from twin.render.shapes import mitsuba_shape
from twin.render.spectra import irregular_spectrum
from twin.render.transforms import look_at, rotate, scale, translate
from twin.validate.envmap_capture import capture_mirror_sphere

__all__ = [
    "Figure46",
    "field_interiors",
    "render_figure46",
    "render_spectral_panel",
    "room_entries",
    "room_lights",
    "write_figure46",
]

_OBSERVER = "CIE 1931 2 Degree Standard Observer"
_CAMERA_POSITION_M = np.array([0.0, -0.22, 0.16])
_CONSTANT = WavelengthGrid(np.array([400.0, 720.0]))
"""Grid of the one-channel (RGB) tables and maps: the same value at both ends, constant."""


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


def _camera(pixels: int) -> PinholeCamera:
    return PinholeCamera(_CAMERA_POSITION_M, 0.055, pixels)


def _xyz_film() -> SampledSpectra:
    return SampledSpectra(FINE_GRID, _cmfs_on(FINE_GRID).T, ("X", "Y", "Z"))


def _render(
    entries: dict, pixels: int, spp: int, channels: SampledSpectra, groups=()
) -> np.ndarray:
    return render_lit(_camera(pixels), channels, entries, groups, spp=spp, seed=3)


def _sample_square(size_m: float) -> dict[str, object]:
    """The BTF's square in its reference plane z = 0 (the plane its textures are rectified to:
    the holder's marks, the truth's sample plane); the parallax of the material's relief is in
    the view-dependent textures."""
    return {"type": "rectangle", "to_world": scale(size_m / 2)}


def _cie_rgb_matrix() -> np.ndarray:
    return colour.RGB_COLOURSPACES["CIE RGB"].matrix_XYZ_to_RGB


def _rgb_table(table: BTFTable | CompressedTable) -> list[BTFTable]:
    """The BTF as three one-channel tables of CIE RGB reflectance (equal energy, white = 1);
    a compressed BTF is decoded one combination at a time. Specular lobes, spectrally flat, are
    the same in every channel."""
    rgb_cmfs = _cie_rgb_matrix() @ _cmfs_on(table.grid).T
    weights = rgb_cmfs / rgb_cmfs.sum(axis=1, keepdims=True)
    rgb = np.maximum(
        np.stack(
            [
                np.stack([table.texture(i, j) @ weights.T for j in range(len(table.view_dirs))])
                for i in range(len(table.light_dirs))
            ]
        ),
        0.0,
    )
    return [
        BTFTable(
            table.light_dirs,
            table.view_dirs,
            rgb[..., [c, c]].astype(np.float32),
            _CONSTANT,
            table.lobes,
        )
        for c in range(3)
    ]


def _rgb_maps(spectral_map: SpectralMap) -> list[SpectralMap]:
    """The map as three one-channel maps of CIE RGB radiance (matching functions, per nm)."""
    wavelengths = spectral_map.grid.wavelengths_nm
    step = wavelengths[1] - wavelengths[0]
    rgb_cmfs = _cie_rgb_matrix() @ _cmfs_on(spectral_map.grid).T
    rgb = np.maximum(np.einsum("hwk,ck->hwc", spectral_map.radiance, rgb_cmfs), 0)
    return [SpectralMap(rgb[..., [c, c]] * step, _CONSTANT) for c in range(3)]


def _flat_film() -> SampledSpectra:
    """One channel of unit area over 400-720 nm: a one-band rendering's value times 1."""
    inside = (FINE_GRID.wavelengths_nm >= 400) & (FINE_GRID.wavelengths_nm <= 720)
    return SampledSpectra(FINE_GRID, (inside / 320.0)[None, :], ("flat",))


@dataclass(frozen=True)
class Figure46:
    """The three panels in XYZ ``(H, W, 3)``, the map's white, the interiors of the matte and of
    the glossy fields, and Delta E94 against the photograph per pixel."""

    photograph: np.ndarray
    spectral: np.ndarray
    rgb: np.ndarray
    white_xyz: np.ndarray
    fields: np.ndarray
    glossy: np.ndarray
    delta_e_spectral: np.ndarray
    delta_e_rgb: np.ndarray
    environment: SpectralMap

    @property
    def mask(self) -> np.ndarray:
        """Pixels of the matte fields' interiors."""
        return self.fields[~self.glossy].any(axis=0)

    def field_delta_e(self) -> tuple[np.ndarray, np.ndarray]:
        """Delta E94 of every field's mean colour (interior), spectral and RGB rendering."""
        return (
            self.field_delta_e_between(self.spectral, self.photograph),
            self.field_delta_e_between(self.rgb, self.photograph),
        )

    def field_delta_e_between(self, image: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """``(n_fields,)`` Delta E94 of every field's mean colour (interior) in ``image`` against
        ``reference``, both XYZ ``(H, W, 3)`` of this figure's camera (e.g. a panel of another
        BTF from :func:`render_spectral_panel`), relative to the map's white."""
        image_means, reference_means = (
            np.array([values[field].mean(axis=0) for field in self.fields])
            for values in (image, reference)
        )
        return colour.delta_E(
            _lab(image_means, self.white_xyz),
            _lab(reference_means, self.white_xyz),
            method="CIE 1994",
        )

    def summary(self) -> dict[str, float]:
        spectral, rgb = self.delta_e_spectral[self.mask], self.delta_e_rgb[self.mask]
        field_spectral, field_rgb = self.field_delta_e()
        matte = ~self.glossy
        return {
            "field_mean_delta_e94_spectral": float(field_spectral[matte].mean()),
            "field_mean_delta_e94_rgb": float(field_rgb[matte].mean()),
            "field_ratio_rgb_over_spectral": float(
                field_rgb[matte].mean() / field_spectral[matte].mean()
            ),
            "field_mean_delta_e94_spectral_glossy": float(field_spectral[~matte].mean()),
            "field_mean_delta_e94_rgb_glossy": float(field_rgb[~matte].mean()),
            "mean_delta_e94_spectral": float(spectral.mean()),
            "mean_delta_e94_rgb": float(rgb.mean()),
            "ratio_rgb_over_spectral": float(rgb.mean() / spectral.mean()),
            "median_delta_e94_spectral": float(np.median(spectral)),
            "median_delta_e94_rgb": float(np.median(rgb)),
            "matte_field_pixels": int(self.mask.sum()),
        }


def _lab(xyz: np.ndarray, white: np.ndarray) -> np.ndarray:
    return colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xyY(white / white[1])[:2])


def field_interiors(material: Material, pixels: int, interior: float = 0.5) -> np.ndarray:
    """``(n_fields, H, W)`` image masks of the central ``interior`` of every chart field's top
    face (the comparison leaves out field edges, where the flat BTF square and the raised fields
    of the true material differ by parallax)."""
    from matplotlib.path import Path as Polygon

    camera = _camera(pixels)
    centres = np.arange(pixels) + 0.5
    x, y = np.meshgrid(centres, centres)
    pixel_centres = np.column_stack([x.ravel(), y.ravel()])
    masks = []
    for part in (p for p in material.parts if p.name.startswith("field_")):
        low, high = part.mesh.bounds
        middle, half = (low + high) / 2, interior * (high - low) / 2
        corners = np.array(
            [
                [middle[0] + sx * half[0], middle[1] + sy * half[1], high[2]]
                for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            ]
        )
        masks.append(Polygon(camera.project(corners)).contains_points(pixel_centres))
    return np.stack(masks).reshape(-1, pixels, pixels)


def render_figure46(
    material: Material,
    table: BTFTable | CompressedTable,
    *,
    pixels: int = 96,
    spp: int = 64,
    map_size: tuple[int, int] = (64, 128),
    map_grid: WavelengthGrid = DEFAULT_GRID,
) -> Figure46:
    """Capture the room's map, render the three panels and compare them (module docstring).

    The mirror sphere is imaged with ``8 * map_size[0]`` pixels across. A white diffuser lit by
    the captured map matches the room within 2 % at 32 x 64 map pixels and 1.4 % at 64 x 128
    (the spots' true directions within their map pixel; see the session notes).
    """
    room, lights = room_entries(), room_lights()
    environment, _ = capture_mirror_sphere(
        room,
        map_grid,
        groups=lights,
        camera_direction=(0.3, -0.4, 1.0),
        pixels=8 * map_size[0],
        spp=64,
        height=map_size[0],
        width=map_size[1],
    )
    true_sample = {part.name: mitsuba_shape(part) for part in material.parts}
    photograph = _render({**room, **true_sample}, pixels, spp, _xyz_film(), lights)
    square = _sample_square(material.size_m)
    spectral = render_spectral_panel(material, table, environment, pixels=pixels, spp=spp)
    channels = []
    for rgb_table, rgb_map in zip(_rgb_table(table), _rgb_maps(environment), strict=True):
        entries = {
            "environment": spectral_envmap(rgb_map),
            "sample": {**square, "bsdf": btf_bsdf(rgb_table)},
        }
        channels.append(_render(entries, pixels, spp, _flat_film())[..., 0])
    rgb = np.einsum("ij,hwj->hwi", np.linalg.inv(_cie_rgb_matrix()), np.stack(channels, -1))
    # White of the scene: a perfect white diffuser facing +z under the map, E / pi in XYZ.
    directions_cos = np.cos((np.arange(map_size[0]) + 0.5) * np.pi / map_size[0])
    weights = environment.solid_angles() * np.maximum(directions_cos, 0)[:, None]
    radiance = np.einsum("hwk,hw->k", environment.radiance, weights) / np.pi
    white = (
        np.einsum("k,kc->c", radiance, _cmfs_on(environment.grid))
        * np.diff(environment.grid.wavelengths_nm)[0]
    )
    reference = _lab(photograph, white)
    fields = field_interiors(material, pixels)
    glossy = np.array(
        [p.roughness is not None for p in material.parts if p.name.startswith("field_")]
    )
    return Figure46(
        photograph,
        spectral,
        rgb,
        white,
        fields,
        glossy,
        colour.delta_E(_lab(spectral, white), reference, method="CIE 1994"),
        colour.delta_E(_lab(rgb, white), reference, method="CIE 1994"),
        environment,
    )


def render_spectral_panel(
    material: Material,
    table: BTFTable | CompressedTable,
    environment: SpectralMap,
    *,
    pixels: int = 96,
    spp: int = 64,
) -> np.ndarray:
    """Panel (b) alone: the BTF on the material's square under a spectral map, recorded through
    the CIE 1931 matching functions, XYZ ``(pixels, pixels, 3)``. With the same map, size and
    samples, two BTFs are rendered with the same random numbers (the BSDF samples the cosine
    hemisphere whatever its values), so their difference is the BTFs'."""
    entries = {
        "environment": spectral_envmap(environment),
        "sample": {**_sample_square(material.size_m), "bsdf": btf_bsdf(table)},
    }
    return _render(entries, pixels, spp, _xyz_film())


def _cmfs_on(grid: WavelengthGrid) -> np.ndarray:
    """CIE 1931 colour matching functions ``(K, 3)`` on ``grid``."""
    cmfs = colour.MSDS_CMFS[_OBSERVER]
    return np.stack(
        [np.interp(grid.wavelengths_nm, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)],
        axis=1,
    )


def write_figure46(figure: Figure46, path: str | Path) -> Path:
    """Three panels (one white balance, one tone curve) and the two Delta E94 maps (matte field
    interiors)."""
    from matplotlib.figure import Figure

    path = Path(path)
    white = figure.white_xyz / figure.white_xyz[1]
    panels = []
    for xyz in (figure.photograph, figure.spectral, figure.rgb):
        adapted = colour.chromatic_adaptation(
            xyz / figure.white_xyz[1],
            white,
            colour.xy_to_XYZ([0.3127, 0.3290]),
            method="Von Kries",
            transform="CAT02",
        )
        panels.append(np.clip(colour.XYZ_to_sRGB(adapted * 1.6, apply_cctf_encoding=True), 0, 1))
    plot = Figure(figsize=(20, 4.5))
    axes = plot.subplots(1, 5)
    titles = ("(a) photograph", "(b) spectral rendering", "(c) RGB rendering")
    for axis, panel, title in zip(axes[:3], panels, titles, strict=True):
        axis.imshow(panel)
        axis.set_title(title)
        axis.axis("off")
    limit = float(np.percentile(figure.delta_e_rgb[figure.mask], 99))
    summary = figure.summary()
    for axis, values, name in (
        (axes[3], figure.delta_e_spectral, "spectral"),
        (axes[4], figure.delta_e_rgb, "rgb"),
    ):
        shown = axis.imshow(np.where(figure.mask, values, np.nan), vmin=0, vmax=limit)
        axis.set_title(
            f"Delta E94 {name}, matte fields: pixels {summary[f'mean_delta_e94_{name}']:.2f}, "
            f"field means {summary[f'field_mean_delta_e94_{name}']:.2f}",
            fontsize=9,
        )
        axis.axis("off")
        plot.colorbar(shown, ax=axis, fraction=0.046)
    plot.tight_layout()
    plot.savefig(path, dpi=100)
    return path
