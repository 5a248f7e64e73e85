"""Reading the declarative YAML of ``scenes/`` into pydantic models, with errors naming fields."""

from __future__ import annotations

from pathlib import Path
from typing import TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from recon.errors import SpectwinInputError

__all__ = ["read_yaml_mapping", "resolve_scene_file", "validate_document"]

Model = TypeVar("Model", bound=BaseModel)


def resolve_scene_file(name_or_path: str | Path, folder: Path, what: str) -> Path:
    """A path as given, or ``folder/<name>.yaml`` for a bare name; raises if it does not exist."""
    path = Path(name_or_path)
    if not path.suffix:
        path = folder / f"{name_or_path}.yaml"
    if not path.is_file():
        known = sorted(candidate.stem for candidate in folder.glob("*.yaml"))
        raise SpectwinInputError(f"{what}: no file {path}; expected a path or one of {known}")
    return path


def read_yaml_mapping(path: Path) -> dict:
    """The YAML document at ``path``, which must be a mapping."""
    try:
        document = yaml.safe_load(path.read_text())
    except yaml.YAMLError as error:
        raise SpectwinInputError(f"{path}: malformed YAML: {error}") from error
    if not isinstance(document, dict):
        raise SpectwinInputError(f"{path}: expected a mapping of settings")
    return document


def validate_document(model: type[Model], document: dict, path: Path) -> Model:
    """Validate ``document`` against ``model``; the error lists every offending field."""
    try:
        return model.model_validate(document)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in item['loc']) or 'document'}: {item['msg']}"
            for item in error.errors()
        )
        raise SpectwinInputError(f"{path}: {problems}") from error
