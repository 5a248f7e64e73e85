"""A user's own sample from files: meshes, spectra, spectral and RGB textures (``material:
user`` in a material YAML; the recipe is in the README).

Each part is a mesh (any format trimesh reads, in the sample frame, z the normal, the sample's
square ``[-size/2, size/2]^2`` around the origin) or a flat patch filling that square, with
a diffuse reflectance covering at least 400-700 nm, held constant beyond its last samples
(one spectrum, a spectral OpenEXR texture in the layout of
:mod:`recon.spectral_exr`, or an sRGB image upsampled by a named method,
:mod:`recon.rgb_upsampling`) and a BSDF (diffuse, a rough dielectric coating, a rough metal,
a clear rough dielectric).
File paths are relative to the YAML file. The result is a :class:`twin.materials.Material`
like the built-ins, so the twin's captures, its truth and its evaluations take it unchanged.
"""

from __future__ import annotations

from pathlib import Path

import colour
import numpy as np
import trimesh

from recon.btf.specular_lobe import COATING_IOR
from recon.errors import InputError
from recon.measured_data import read_spectra_csv
from recon.rgb_upsampling import read_srgb_image, reduce_image, upsample_srgb
from recon.spectra import SampledSpectra, from_colour, resample
from recon.spectral_exr import read_spectral_exr
from twin.components.lamps import FINE_GRID
from twin.components.targets import colorchecker_reflectances
from twin.materials.config import (
    RGBTextureConfig,
    SpectrumConfig,
    UserMaterialConfig,
    UserPartConfig,
)
from twin.materials.surfaces import MATERIAL_GRID, SurfacePart, texture_coordinates

__all__ = ["PATCH_HEIGHT_M", "build_user", "flat_patch"]

PATCH_HEIGHT_M = 0.0003
"""Height of a flat patch above the holder's plate (z = 0)."""

_BANDS_NM = (400.0, 700.0)  # a reflectance must cover these; beyond its data it is held
_BELOW_M = 0.002  # how far below the holder's plane a mesh may reach


def flat_patch(size_m: float) -> trimesh.Trimesh:
    """The sample's square as two triangles :data:`PATCH_HEIGHT_M` above the holder's plate
    (a card's thickness; on the plate itself the two surfaces would fight), u along x, v
    along y."""
    half, z = size_m / 2, PATCH_HEIGHT_M
    vertices = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return trimesh.Trimesh(
        vertices,
        np.array([[0, 1, 2], [0, 2, 3]]),
        visual=trimesh.visual.TextureVisuals(uv=uv),
        process=False,
    )


def _file(folder: Path, name: str | None, field: str) -> Path:
    if name is None:
        raise InputError(f"{field}: expected a file name")
    path = Path(name) if Path(name).is_absolute() else folder / name
    if not path.is_file():
        raise InputError(f"{field}: no file {path}")
    return path


def _mesh(config: UserPartConfig, folder: Path, size_m: float) -> trimesh.Trimesh:
    field = f"parts.{config.name}.mesh"
    if config.mesh is None:
        return flat_patch(size_m)
    path = _file(folder, config.mesh, field)
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise InputError(f"{field}: {path} is not a mesh trimesh reads ({error})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError(f"{field}: {path} holds no triangles")
    mesh.apply_scale(config.mesh_scale)
    low, high = mesh.bounds
    reach = np.abs(np.concatenate([low[:2], high[:2]])).max()
    if reach > size_m / 2 * 1.001 or low[2] < -_BELOW_M:
        raise InputError(
            f"{field}: {path.name} spans x, y to {1e3 * reach:.1f} mm and z from "
            f"{1e3 * low[2]:.1f} mm; "
            f"expected metres (mesh_scale) within the {1e3 * size_m:.0f} mm square around the "
            f"origin, above z = {-1e3 * _BELOW_M:.0f} mm"
        )
    return mesh


def _covering(spectra: SampledSpectra, field: str) -> SampledSpectra:
    wavelengths = spectra.wavelengths_nm
    if wavelengths[0] > _BANDS_NM[0] or wavelengths[-1] < _BANDS_NM[1]:
        raise InputError(
            f"{field}: covers {wavelengths[0]:g}-{wavelengths[-1]:g} nm; expected at least "
            f"{_BANDS_NM[0]:g}-{_BANDS_NM[1]:g} nm"
        )
    return spectra


def _colour_spectrum(entry: str, field: str) -> SampledSpectra:
    datasets = dict(colour.SDS_COLOURCHECKERS)
    datasets["CIE 1995 TCS"] = colour.quality.SDS_TCS["CIE 1995"]
    datasets["NIST CQS 9.0 VS"] = colour.quality.SDS_VS["NIST CQS 9.0"]
    dataset, _, name = entry.rpartition("/")
    if dataset not in datasets or name not in datasets[dataset]:
        known = ", ".join(sorted(datasets))
        raise InputError(
            f"{field}: no spectrum {entry!r}; expected '<dataset>/<name>' with a dataset of {known}"
        )
    return from_colour(datasets[dataset][name])


def _csv_column(path: Path, column: str | None, field: str) -> SampledSpectra:
    table = read_spectra_csv(path.resolve())
    names = table.names or ()
    if column is None and len(names) > 1:
        raise InputError(f"{field}: {path} has the columns {list(names)}; name one with column")
    if column is not None and column not in names:
        raise InputError(f"{field}: {path} has no column {column!r}: {list(names)}")
    return SampledSpectra(table.grid, table.values[names.index(column or names[0])])


def _spectrum(config: SpectrumConfig, folder: Path, field: str) -> SampledSpectra:
    if config.chart is not None:
        return colorchecker_reflectances(MATERIAL_GRID).row(config.chart)
    if config.colour is not None:
        spectrum = _colour_spectrum(config.colour, f"{field}.colour")
    else:
        path = _file(folder, config.csv, f"{field}.csv")
        spectrum = _csv_column(path, config.column, f"{field}.csv")
    return _covering(spectrum, field)


def _rgb_texture(config: RGBTextureConfig, folder: Path, field: str) -> SampledSpectra:
    full = read_srgb_image(_file(folder, config.image, f"{field}.image"))
    linear, factor = reduce_image(full, config.max_texels)
    if config.method == "jakob2019":
        return upsample_srgb(linear, "jakob2019")
    path = _file(folder, config.known_spectra, f"{field}.known_spectra")
    spectra = _covering(read_spectra_csv(path.resolve()), f"{field}.known_spectra")
    pixels = np.asarray(config.known_pixels) // factor  # the reduced image's pixel of each spot
    return upsample_srgb(linear, "spectralization", known_pixels=pixels, known_spectra=spectra)


def _texture(config: UserPartConfig, folder: Path) -> SampledSpectra | None:
    field = f"parts.{config.name}"
    if config.rgb_texture is not None:
        return _rgb_texture(config.rgb_texture, folder, f"{field}.rgb_texture")
    if config.texture is None:
        return None
    image = read_spectral_exr(_file(folder, config.texture, f"{field}.texture"))
    if image.kind != "reflective":
        raise InputError(
            f"{field}.texture: holds {image.kind} values; expected a reflective spectral EXR"
        )
    return _covering(SampledSpectra(image.grid, image.cube), f"{field}.texture")


def _part(config: UserPartConfig, folder: Path, size_m: float) -> SurfacePart:
    field = f"parts.{config.name}"
    mesh = _mesh(config, folder, size_m)
    texture = _texture(config, folder)
    if texture is not None:
        if texture_coordinates(mesh) is None:
            raise InputError(f"{field}.mesh: a textured part needs a mesh with texture coordinates")
        reflectance = SampledSpectra(texture.grid, texture.values.mean(axis=(0, 1)))
    elif config.spectrum is not None:
        reflectance = _spectrum(config.spectrum, folder, f"{field}.spectrum")
    else:
        reflectance = SampledSpectra(MATERIAL_GRID, np.ones(MATERIAL_GRID.size))
    bsdf = config.bsdf
    try:
        return SurfacePart(
            config.name,
            mesh,
            resample(
                resample(reflectance, MATERIAL_GRID, out_of_range="clamp"),
                FINE_GRID,
                out_of_range="clamp",
            ),
            roughness=bsdf.roughness,
            conductor=bsdf.metal,
            texture=texture,
            dielectric_ior=(bsdf.ior or COATING_IOR) if bsdf.type == "rough_dielectric" else None,
        )
    except InputError as error:
        raise InputError(f"{field}: {error}") from None


def build_user(config: UserMaterialConfig, folder: Path):
    """Parts, design spectra (each part's reflectance, a texture's mean, on ``MATERIAL_GRID``)
    and no metameric pairs of a user's material whose files lie relative to ``folder``."""
    parts = [_part(part, folder, config.size_m) for part in config.parts]
    spectra = {
        part.name: resample(part.reflectance, MATERIAL_GRID, out_of_range="clamp") for part in parts
    }
    return parts, spectra, ()
