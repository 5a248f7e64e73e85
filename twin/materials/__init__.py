"""Ground-truth materials with exactly known spectral reflectance (``scenes/materials``).

A material is a set of surface parts in the sample frame plus the spectra they were designed
with (on ``MATERIAL_GRID``) and the pairs of parts designed to be metameric for the dome camera.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import TypeAdapter

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.materials.builders import (
    MATERIAL_GRID,
    build_colorchecker16,
    build_fabric,
    build_lego,
    build_wallpaper,
)
from twin.materials.config import MaterialConfig
from twin.materials.surfaces import SurfacePart
from twin.rigs.yaml_config import (
    read_yaml_mapping,
    resolve_scene_file,
    scene_folder,
    scene_names,
    validate_document,
)

__all__ = ["MATERIAL_DIR", "MATERIAL_GRID", "Material", "available_materials", "load_material"]

MATERIAL_DIR = scene_folder("materials")

_BUILDERS: dict[str, Callable[[Any], Any]] = {  # each builder takes its own kind of config
    "colorchecker16": build_colorchecker16,
    "red_fabric": build_fabric,
    "lego": build_lego,
    "wallpaper": build_wallpaper,
}


@dataclass(frozen=True, eq=False)
class Material:
    """A built material: parts to render, design spectra, metameric part pairs."""

    name: str
    size_m: float
    parts: tuple[SurfacePart, ...]
    spectra: dict[str, SampledSpectra]
    metameric_pairs: tuple[tuple[str, str], ...]


class _Document:
    """pydantic needs a model to validate the discriminated union against."""

    adapter = TypeAdapter(MaterialConfig)

    @classmethod
    def model_validate(cls, document: dict) -> MaterialConfig:
        return cls.adapter.validate_python(document)


def available_materials() -> list[str]:
    return scene_names(MATERIAL_DIR)


def load_material(name_or_path: str | Path) -> Material:
    """Build the material described by ``scenes/materials/<name>.yaml`` (or a path; a user's
    material, :mod:`twin.materials.user`, reads its files relative to its YAML file)."""
    path = resolve_scene_file(name_or_path, MATERIAL_DIR, "material")
    config = validate_document(_Document, read_yaml_mapping(path), path)
    if config.material == "user":
        from twin.materials.user import build_user  # reads files, upsamples RGB: only when used

        try:
            parts, spectra, pairs = build_user(config, path.parent)
        except InputError as error:
            raise InputError(f"{path}: {error}") from None
    else:
        parts, spectra, pairs = _BUILDERS[config.material](config)
    return Material(config.name, config.size_m, tuple(parts), spectra, tuple(pairs))
