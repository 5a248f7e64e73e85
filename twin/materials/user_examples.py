"""Two user materials made from files only, as starting points for one's own
(``spectwin material examples``):

- ``printed_tile``: a gently embossed tile (an OBJ mesh in millimetres, with texture
  coordinates) under a spectral OpenEXR texture of measured reflectances (a Voronoi mosaic of
  eight of the RAW-to-ACES training spectra that ship with spectwin), with a rough dielectric
  coating;
- ``painted_card``: a flat card photographed as an sRGB PNG (three DuPont paint chips in
  shaded cells, the same data), upsampled to spectra by the project's spectralization from
  the three chips' spectra measured at one pixel each.

Their true spectra are known, so the upsampling itself can be checked as well as the capture.
"""

from __future__ import annotations

from pathlib import Path

import colour
import numpy as np
import trimesh
from skimage import io

from recon.experiments.synthetic_images import material_mosaic
from recon.measured_data import read_spectra_csv
from recon.rgb_upsampling import srgb_response
from recon.spectra import DEFAULT_GRID, SampledSpectra, resample
from recon.spectral_exr import write_spectral_exr
from twin.materials.builders import MATERIAL_GRID
from twin.materials.geometry import height_field

__all__ = ["EXAMPLE_NAMES", "example_card_truth", "write_user_examples"]

EXAMPLE_NAMES = ("printed_tile", "painted_card")

_TILE_YAML = """\
# A user's material: an embossed tile (mesh in mm, with texture coordinates) under a spectral
# OpenEXR texture of reflectance, coated with a rough dielectric. Paths are relative to this file.
name: printed tile
material: user
size_m: 0.04
parts:
  - name: tile
    mesh: tile.obj
    mesh_scale: 0.001
    texture: tile_reflectance.exr
    bsdf: {type: rough_plastic, roughness: 0.3}
"""

_CARD_YAML = """\
# A user's material: a flat card known from an sRGB photograph (card.png, under D65, white
# balanced) and three spectra measured on it at the given pixels (row, column), upsampled by the
# spectralization (thesis Eq. 6.10).
name: painted card
material: user
size_m: 0.04
parts:
  - name: card
    rgb_texture:
      image: card.png
      method: spectralization
      known_spectra: spots.csv
      known_pixels: {pixels}
"""

_CARD_CHIPS = ("s000", "s067", "s013")  # a red, a green and a blue chip, all within sRGB


def _tile(folder: Path) -> Path:
    side = 49
    coordinates = np.linspace(-1.0, 1.0, side)
    x, y = np.meshgrid(coordinates, coordinates, indexing="xy")
    heights_mm = 0.4 + 0.3 * np.cos(3 * np.pi * x) * np.cos(3 * np.pi * y)
    mesh = height_field(heights_mm, 40.0)
    mesh.visual = trimesh.visual.TextureVisuals(uv=(mesh.vertices[:, :2] + 20.0) / 40.0)
    text = trimesh.exchange.obj.export_obj(mesh, include_texture=True, return_texture=True)[0]
    lines = [line for line in text.splitlines() if not line.startswith(("mtllib", "usemtl"))]
    (folder / "tile.obj").write_text("\n".join(lines) + "\n")
    spectra = read_spectra_csv("spectra/reflectances/rawtoaces_training_190.csv")
    chosen = resample(SampledSpectra(spectra.grid, spectra.values[::24][:8]), MATERIAL_GRID)
    texture, _ = material_mosaic(chosen.values, (32, 32), cells=24, shading=(0.85, 1.0), seed=5)
    write_spectral_exr(
        folder / "tile_reflectance.exr",
        np.clip(texture, 0, 1).astype(np.float32),
        MATERIAL_GRID,
        kind="reflective",
    )
    path = folder / "printed_tile.yaml"
    path.write_text(_TILE_YAML)
    return path


def example_card_truth() -> tuple[SampledSpectra, np.ndarray]:
    """The painted card's true reflectance ``(64, 64, 33)`` on ``DEFAULT_GRID`` and the
    ``(3, 2)`` pixels where its three chips' spectra are given."""
    chips = read_spectra_csv("spectra/reflectances/dupont_paint_chips.csv")
    spectra = np.stack([chips.row(name).values for name in _CARD_CHIPS])
    on_grid = resample(SampledSpectra(chips.grid, spectra), DEFAULT_GRID, out_of_range="clamp")
    texture, labels = material_mosaic(
        on_grid.values, (64, 64), cells=12, shading=(1.0, 1.0), seed=3
    )
    pixels = np.array([np.argwhere(labels == chip)[0] for chip in range(len(_CARD_CHIPS))])
    return SampledSpectra(DEFAULT_GRID, texture), pixels


def _card(folder: Path) -> Path:
    truth, pixels = example_card_truth()
    linear = np.clip(truth.values @ srgb_response(), 0, 1)
    encoded = colour.cctf_encoding(linear, function="sRGB")
    io.imsave(folder / "card.png", np.round(255 * encoded).astype(np.uint8), check_contrast=False)
    chips = read_spectra_csv("spectra/reflectances/dupont_paint_chips.csv")
    rows = [chips.row(name).values for name in _CARD_CHIPS]
    table = np.column_stack([chips.wavelengths_nm, *rows])
    header = "wavelength_nm," + ",".join(_CARD_CHIPS)
    np.savetxt(folder / "spots.csv", table, delimiter=",", header=header, comments="", fmt="%.6g")
    path = folder / "painted_card.yaml"
    path.write_text(_CARD_YAML.format(pixels=pixels.tolist()))
    return path


def write_user_examples(folder: str | Path) -> list[Path]:
    """Write the example materials (module docstring) into ``folder``, one subfolder each;
    returns their YAML files."""
    folder = Path(folder)
    written = []
    for name, writer in zip(EXAMPLE_NAMES, (_tile, _card), strict=True):
        (folder / name).mkdir(parents=True, exist_ok=True)
        written.append(writer(folder / name))
    return written
