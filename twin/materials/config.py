"""Schema of ``scenes/materials/*.yaml``: which ground-truth material and its parameters, or a
user's own sample made from files (``material: user``, :mod:`twin.materials.user`)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from twin.rigs.yaml_config import Positive, StrictModel

__all__ = [
    "BSDFConfig",
    "CONDUCTOR_PRESETS",
    "ColorChecker16Config",
    "FabricConfig",
    "LegoConfig",
    "MaterialConfig",
    "RGBTextureConfig",
    "SpectrumConfig",
    "UserMaterialConfig",
    "UserPartConfig",
    "WallpaperConfig",
]


class _Material(StrictModel):
    """Fields every material has: a display name, the side of its square, a design seed."""

    name: str
    size_m: Annotated[float, Field(gt=0, le=0.05)]
    seed: int = 0


class ColorChecker16Config(_Material):
    material: Literal["colorchecker16"]
    fields: Annotated[list[str], Field(min_length=16, max_length=16)]
    glossy_fields: list[str] = []
    gloss_roughness: Annotated[float, Field(gt=0, le=1)] = 0.08

    @model_validator(mode="after")
    def _glossy_are_fields(self) -> ColorChecker16Config:
        unknown = set(self.glossy_fields) - set(self.fields)
        if unknown:
            raise ValueError(f"glossy_fields: {sorted(unknown)} are not among the fields")
        return self


class FabricConfig(_Material):
    material: Literal["red_fabric"]
    threads_per_direction: Annotated[int, Field(ge=2, le=64)]
    thread_radius_m: Positive


class LegoConfig(_Material):
    material: Literal["lego"]
    colours: Annotated[list[str], Field(min_length=3, max_length=3)]
    roughness: Annotated[float, Field(gt=0, le=1)] = 0.05


class WallpaperConfig(_Material):
    material: Literal["wallpaper"]
    resolution: Annotated[int, Field(ge=8, le=512)]
    emboss_height_m: Positive
    pattern_period_m: Positive
    paper_colour: str
    print_colour: str
    roughness: Annotated[float, Field(gt=0, le=1)] = 0.25


def _exactly_one(model: StrictModel, names: tuple[str, ...], what: str) -> None:
    given = [name for name in names if getattr(model, name) is not None]
    if len(given) != 1:
        raise ValueError(f"expected exactly one of {', '.join(names)} for {what}, got {given}")


class SpectrumConfig(StrictModel):
    """One reflectance spectrum: a CSV file (header ``wavelength_nm,<name>,...``; ``column``
    picks one of several), a ``colour`` dataset entry ``"<dataset>/<name>"`` (a ColorChecker
    of ``colour.SDS_COLOURCHECKERS``, ``"CIE 1995 TCS"`` or ``"NIST CQS 9.0 VS"``), or
    ``chart``, a patch of the ColorChecker the built-in materials use."""

    csv: str | None = None
    column: str | None = None
    colour: str | None = None
    chart: str | None = None

    @model_validator(mode="after")
    def _one_source(self) -> SpectrumConfig:
        _exactly_one(self, ("csv", "colour", "chart"), "a spectrum")
        if self.column is not None and self.csv is None:
            raise ValueError("column: names a column of a csv file; give csv too")
        return self


class RGBTextureConfig(StrictModel):
    """An sRGB image upsampled to spectra by ``method`` (:mod:`recon.rgb_upsampling`); the
    spectralization takes ``known_spectra`` (a CSV, one column per spot) measured at
    ``known_pixels`` (row, column of the image, in the CSV's column order)."""

    image: str
    method: Literal["jakob2019", "spectralization"]
    known_spectra: str | None = None
    known_pixels: list[tuple[int, int]] | None = None
    max_texels: Annotated[int, Field(ge=1, le=1024)] = 256

    @model_validator(mode="after")
    def _spots_for_spectralization(self) -> RGBTextureConfig:
        spots = (self.known_spectra, self.known_pixels)
        if self.method == "spectralization" and None in spots:
            raise ValueError("method spectralization: give known_spectra and known_pixels")
        if self.method == "jakob2019" and spots != (None, None):
            raise ValueError("method jakob2019: takes no known_spectra or known_pixels")
        return self


CONDUCTOR_PRESETS = (
    "a-C", "Ag", "Al", "AlAs", "AlSb", "Au", "Be", "Cr", "Cu", "Cu2O", "CuO", "Hg", "HgTe",
    "Ir", "K", "Li", "MgO", "Mo", "Na_palik", "Nb", "Ni_palik", "Rh", "Se", "SiC", "Ta", "Te",
    "TiC", "TiN", "TiO2", "VC", "V_palik", "VN", "W",
)  # fmt: skip
"""Metals whose complex index Mitsuba 3 tabulates (its ``conductor`` presets)."""


class BSDFConfig(StrictModel):
    """A part's scattering: ``diffuse`` (Lambertian), ``rough_plastic`` (a rough dielectric
    coating of index 1.5 over the diffuse base), ``rough_conductor`` (a metal of Mitsuba's
    presets, e.g. ``Ag``, ``Al``, ``Au``, ``Cu``) or ``rough_dielectric`` (a clear dielectric of
    index ``ior``, 1.5 if not given, with no base: glass, a clear resin or film); each rough
    one with the Beckmann ``roughness`` of its microfacets (Mitsuba's distribution)."""

    type: Literal["diffuse", "rough_plastic", "rough_conductor", "rough_dielectric"] = "diffuse"
    roughness: Annotated[float, Field(gt=0, le=1)] | None = None
    metal: str | None = None
    ior: Annotated[float, Field(gt=1, le=3)] | None = None

    @model_validator(mode="after")
    def _parameters_of_type(self) -> BSDFConfig:
        if self.type != "diffuse" and self.roughness is None:
            raise ValueError(f"type {self.type}: needs a roughness in (0, 1]")
        if self.type == "diffuse" and self.roughness is not None:
            raise ValueError("type diffuse: takes no roughness")
        if (self.type == "rough_conductor") != (self.metal is not None):
            raise ValueError("metal: given exactly for type rough_conductor")
        if self.ior is not None and self.type != "rough_dielectric":
            raise ValueError("ior: given only for type rough_dielectric")
        if self.metal is not None and self.metal not in CONDUCTOR_PRESETS:
            raise ValueError(
                f"metal: {self.metal!r} is not one of Mitsuba's presets {list(CONDUCTOR_PRESETS)}"
            )
        return self


class UserPartConfig(StrictModel):
    """One part of a user's sample: its geometry (``mesh``, a file trimesh reads, in the sample
    frame with z the normal, scaled to metres by ``mesh_scale``; omitted: a flat patch filling
    the sample's square), its diffuse reflectance (exactly one of ``spectrum``, ``texture``, a
    spectral OpenEXR of reflectance, or ``rgb_texture``) and its ``bsdf``."""

    name: Annotated[str, Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")]
    mesh: str | None = None
    mesh_scale: Positive = 1.0
    spectrum: SpectrumConfig | None = None
    texture: str | None = None
    rgb_texture: RGBTextureConfig | None = None
    bsdf: BSDFConfig = BSDFConfig()

    @model_validator(mode="after")
    def _one_reflectance(self) -> UserPartConfig:
        if self.bsdf.type in ("rough_conductor", "rough_dielectric"):
            if (self.spectrum, self.texture, self.rgb_texture) != (None, None, None):
                raise ValueError(
                    "a rough_conductor's colour is its metal's and a rough_dielectric is clear; "
                    "give no reflectance"
                )
            return self
        _exactly_one(self, ("spectrum", "texture", "rgb_texture"), f"part {self.name}")
        return self


class UserMaterialConfig(_Material):
    material: Literal["user"]
    parts: Annotated[list[UserPartConfig], Field(min_length=1, max_length=64)]

    @model_validator(mode="after")
    def _unique_part_names(self) -> UserMaterialConfig:
        names = [part.name for part in self.parts]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise ValueError(f"parts: the names {repeated} are used more than once")
        return self


MaterialConfig = Annotated[
    ColorChecker16Config | FabricConfig | LegoConfig | WallpaperConfig | UserMaterialConfig,
    Field(discriminator="material"),
]
