"""Reading the declarative YAML of ``scenes/`` into pydantic models, with errors naming fields."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Protocol, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from recon.errors import InputError

__all__ = [
    "NonNegative",
    "Positive",
    "StrictModel",
    "read_yaml_mapping",
    "resolve_scene_file",
    "scene_folder",
    "scene_names",
    "validate_document",
]

Model = TypeVar("Model", covariant=True)


class Validator(Protocol[Model]):
    """A pydantic model class, or anything that validates a document the same way."""

    def model_validate(self, obj: Any, /) -> Model: ...


Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]


class StrictModel(BaseModel):
    """Base of every scene schema: unknown keys are errors, loaded settings are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def scene_folder(kind: str) -> Path:
    """The folder of the shipped scene files of one kind: ``"rigs"``, ``"cameras"``,
    ``"materials"`` (package data of :mod:`scenes`)."""
    return Path(str(resources.files("scenes").joinpath(kind)))


def scene_names(folder: Path) -> list[str]:
    """Names (file stems) of the YAML files in a ``scenes/`` folder."""
    return sorted(path.stem for path in folder.glob("*.yaml"))


def resolve_scene_file(name_or_path: str | Path, folder: Path, what: str) -> Path:
    """A path as given, or ``folder/<name>.yaml`` for a bare name; raises if it does not exist."""
    path = Path(name_or_path)
    if not path.suffix:
        path = folder / f"{name_or_path}.yaml"
    if not path.is_file():
        raise InputError(f"{what}: no file {path}; expected a path or one of {scene_names(folder)}")
    return path


def read_yaml_mapping(path: Path) -> dict:
    """The YAML document at ``path``, which must be a mapping."""
    try:
        document = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as error:
        raise InputError(f"{path}: malformed YAML: {error}") from error
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: not a readable YAML text file ({error})") from error
    if not isinstance(document, dict):
        raise InputError(f"{path}: expected a mapping of settings")
    return document


def validate_document(model: Validator[Model], document: dict, path: Path) -> Model:
    """Validate ``document`` against ``model``; the error lists every offending field."""
    try:
        return model.model_validate(document)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in item['loc']) or 'document'}: "
            f"{item['msg'].removeprefix('Value error, ')}"
            for item in error.errors()
        )
        raise InputError(f"{path}: {problems}") from error
