"""Schema of ``scenes/materials/*.yaml``: which ground-truth material and its parameters."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from twin.rigs.yaml_config import Positive, StrictModel

__all__ = [
    "ColorChecker16Config",
    "FabricConfig",
    "LegoConfig",
    "MaterialConfig",
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


MaterialConfig = Annotated[
    ColorChecker16Config | FabricConfig | LegoConfig | WallpaperConfig,
    Field(discriminator="material"),
]
