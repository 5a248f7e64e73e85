"""Sweep files: a base rig, a material, the parameters to vary and the objectives of the front.

A sweep file (YAML; the built-in ones are in ``scenes/sweeps``)::

    name: Gonioreflectometer lamp x filter x direction sampling
    rig: gonio                      # a rig in scenes/rigs or a path
    material: colorchecker16        # a material in scenes/materials
    seed: 0
    plan: {pixels: 128, texels: 32} # the capture and processing settings held fixed
    parameters:                     # each a list of values or a range
      rig.lamps.*.spectrum: [hmi, qth]
      rig.camera.filter: [VS-07, VS-10, VS-20]
      rig.exposure.white_fill: {start: 0.6, stop: 0.9, num: 4}
      plan.rings: [[[0, 1], [30, 4]], [[0, 1], [30, 8]]]
    objectives: [capture_time_h, error_pct]

A parameter is named by its path: ``rig.`` and the rig file's keys (list items by number, ``*``
for every item), ``plan.`` and a field of the plan (:class:`twin.studies.sweep_plans.GonioPlan`
for the gonioreflectometer, :class:`twin.studies.sweep_plans.DomePlan` for the dome), or
``material``. The design points are every combination of the values (their cartesian
product), numbered in that order. Every point's rig and plan are validated (:func:`load_sweep`,
then :func:`check_points` with the kind's check) before anything is captured, so an unknown
path, an empty range or a value outside the rig model's bounds stops the sweep with one line
naming the parameter, the value and what was expected.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
from pydantic import Field, field_validator

from recon.errors import InputError
from twin.materials import available_materials
from twin.output_format import format_value
from twin.rigs.rig_config import load_rig
from twin.rigs.yaml_config import (
    StrictModel,
    read_yaml_mapping,
    resolve_scene_file,
    scene_folder,
    validate_document,
)

__all__ = [
    "SWEEP_DIR",
    "DesignPoint",
    "Sweep",
    "SweepKind",
    "SweepRange",
    "check_points",
    "load_sweep",
    "value_label",
]

SWEEP_DIR = scene_folder("sweeps")
_MAX_POINTS = 10_000
Config = TypeVar("Config", bound=StrictModel)
Plan = TypeVar("Plan", bound=StrictModel)


@dataclass(frozen=True)
class SweepKind:
    """What a sweep needs of a kind of rig: the models of its rig file (``config``) and of a
    point's plan (``plan``), its measures with their units, and the functions that ``check``
    a design point against what the rig can take and ``measure`` it (``measure(point,
    folder)``)."""

    config: type[StrictModel]
    plan: type[StrictModel]
    measures: dict[str, str]
    check: Callable[[DesignPoint], None]
    measure: Callable[[DesignPoint, Path], dict]


class SweepRange(StrictModel):
    """Evenly spaced values from ``start`` to ``stop`` (both included): ``num`` of them, or every
    ``step``; whole numbers stay whole when ``start``, ``stop`` and ``step`` are."""

    start: float
    stop: float
    num: Annotated[int, Field(ge=1)] | None = None
    step: Annotated[float, Field(gt=0)] | None = None

    def values(self) -> list[float | int]:
        if (self.num is None) == (self.step is None):
            raise ValueError("expected exactly one of num and step")
        if self.stop < self.start:
            raise ValueError(f"empty range: stop {self.stop} is below start {self.start}")
        values: np.ndarray
        if self.num is not None:
            values = np.linspace(self.start, self.stop, self.num)
        elif self.step is not None:
            count = int(np.floor((self.stop - self.start) / self.step + 1e-9)) + 1
            values = self.start + self.step * np.arange(count)
        whole = all(float(v).is_integer() for v in (self.start, self.stop, self.step or 1))
        if whole and (self.num is None or np.allclose(values, np.round(values))):
            return [int(round(v)) for v in values]
        return [float(v) for v in values]


class SweepFile(StrictModel):
    """The schema of a sweep file (module docstring)."""

    name: str
    rig: str
    material: str = "colorchecker16"
    seed: Annotated[int, Field(ge=0)] = 0
    plan: dict[str, Any] = {}
    parameters: Annotated[dict[str, list[Any] | SweepRange], Field(min_length=1)]
    objectives: tuple[str, str] = ("capture_time_h", "error_pct")

    @field_validator("parameters")
    @classmethod
    def _not_empty(cls, parameters: dict) -> dict:
        for path, values in parameters.items():
            if isinstance(values, list) and not values:
                raise ValueError(f"{path}: empty list of values; give at least one")
        return parameters


@dataclass(frozen=True)
class DesignPoint:
    """One design of the sweep: its number, the varied values, the resolved rig and plan, and
    where it comes from (the file and its values, for errors)."""

    index: int
    values: dict[str, Any]
    material: str
    rig: StrictModel
    plan: StrictModel
    seed: int
    where: str

    @property
    def label(self) -> str:
        """The varied values in short, e.g. ``qth, VS-20, 5 directions``."""
        return ", ".join(value_label(path, value) for path, value in self.values.items())

    @property
    def key(self) -> str:
        """Folder name of the point: its number and a digest of its design (a changed sweep
        file never reuses another design's results)."""
        design = {"values": self.values, "material": self.material, "seed": self.seed}
        design |= {"rig": self.rig.model_dump(mode="json"), "plan": self.plan.model_dump()}
        digest = hashlib.sha256(json.dumps(design, sort_keys=True).encode()).hexdigest()[:10]
        return f"{self.index:04d}-{digest}"

    def typed(self, config: type[Config], plan: type[Plan]) -> tuple[Config, Plan]:
        """The rig and plan of the point as the kind's models ``config`` and ``plan`` (what
        :func:`load_sweep` validated them as); another kind's point is refused."""
        if isinstance(self.rig, config) and isinstance(self.plan, plan):
            return self.rig, self.plan
        raise InputError(f"{self.where}: expected a design point of {config.__name__}")


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: its file, the kind of rig (``gonioreflectometer`` or ``dome``), the
    points, the objectives and the measures of every point with their units."""

    path: Path
    name: str
    kind: str
    parameters: dict[str, list[Any]]
    points: list[DesignPoint]
    objectives: tuple[str, str]
    measures: dict[str, str]

    def describe(self) -> dict[str, Any]:
        return {
            "sweep": self.name,
            "file": str(self.path),
            "rig": self.kind,
            "parameters": {path: len(values) for path, values in self.parameters.items()},
            "points": len(self.points),
            "objectives": list(self.objectives),
        }


def value_label(path: str, value: Any) -> str:
    """A parameter's value in short: a name as it is, a direction sampling by its number of
    directions, a number after its field's name."""
    if path == "plan.rings":
        return f"{sum(int(count) for _, count in value)} directions"
    if isinstance(value, str):
        return value
    return f"{path.rsplit('.', 1)[-1]} {format_value(value)}"


def _set_path(document: Any, parts: list[str], value: Any, path: str) -> None:
    """Set ``parts`` (keys, item numbers, ``*``) in ``document`` to ``value``; raise naming
    ``path`` where the document has no such key."""
    head, rest = parts[0], parts[1:]
    if isinstance(document, list):
        if head == "*":
            targets: range | list[int] = range(len(document))
        elif head.isdigit() and int(head) < len(document):
            targets = [int(head)]
        else:
            raise InputError(
                f"parameters: {path}: {head!r} is not an item of a list of {len(document)}; "
                "expected an item number or '*'"
            )
        for target in targets:
            if rest:
                _set_path(document[target], rest, value, path)
            else:
                document[target] = copy.deepcopy(value)
        return
    if not isinstance(document, dict) or head not in document:
        known = sorted(document) if isinstance(document, dict) else []
        raise InputError(f"parameters: {path}: unknown key {head!r}; expected one of {known}")
    if rest:
        _set_path(document[head], rest, value, path)
    else:
        document[head] = copy.deepcopy(value)


def _values(path: str, values: list[Any] | SweepRange) -> list[Any]:
    if isinstance(values, list):
        return values
    try:
        return values.values()
    except ValueError as error:
        raise InputError(f"parameters: {path}: {error}") from None


def _check_path(path: str, rig: dict, plan_fields: set[str]) -> None:
    stage, _, rest = path.partition(".")
    if path == "material":
        return
    if stage == "rig" and rest:
        _set_path(copy.deepcopy(rig), rest.split("."), None, path)
        return
    if stage == "plan" and rest in plan_fields:
        return
    if stage == "plan":
        raise InputError(
            f"parameters: {path}: unknown plan field; expected one of "
            f"{sorted('plan.' + name for name in plan_fields)}"
        )
    raise InputError(
        f"parameters: {path}: expected a path starting with 'rig.' or 'plan.', or 'material'"
    )


def _point(
    index: int, values: dict[str, Any], sweep: SweepFile, rig: dict, kind: SweepKind, path: Path
) -> DesignPoint:
    document, plan, material = copy.deepcopy(rig), dict(sweep.plan), sweep.material
    for name, value in values.items():
        stage, _, rest = name.partition(".")
        if name == "material":
            material = value
        elif stage == "rig":
            _set_path(document, rest.split("."), value, name)
        else:
            plan[rest] = value
    where = f"{path}: point {index} ({', '.join(f'{k}={v!r}' for k, v in values.items())})"
    if material not in available_materials():
        raise InputError(
            f"{where}: material: expected one of {available_materials()}, got {material!r}"
        )
    config = validate_document(kind.config, document, Path(f"{where}: rig"))
    plan_model = validate_document(kind.plan, plan, Path(f"{where}: plan"))
    return DesignPoint(index, values, material, config, plan_model, sweep.seed, where)


def check_points(sweep: Sweep, check: Callable[[DesignPoint], None]) -> None:
    """Run ``check`` (the kind's, e.g. :func:`twin.studies.sweep_gonio.check_gonio_point`) on
    every point: the plan against what the rig can take. Raises :class:`InputError`
    naming the file, the point and its values."""
    for point in sweep.points:
        try:
            check(point)
        except InputError as error:
            raise InputError(f"{point.where}: plan: {error}") from None


def load_sweep(name_or_path: str | Path, kind_of: Callable[[str], SweepKind]) -> Sweep:
    """Read and validate a sweep file (a name in ``scenes/sweeps`` or a path), every design
    point's rig and plan included (what the rig can take of a plan: :func:`check_points`);
    ``kind_of(rig)`` gives the :class:`SweepKind` of the rig named in the rig file. Raises
    :class:`InputError` naming the first problem."""
    path = resolve_scene_file(name_or_path, SWEEP_DIR, "sweep file")
    sweep = validate_document(SweepFile, read_yaml_mapping(path), path)
    rig_path = resolve_scene_file(sweep.rig, scene_folder("rigs"), "rig")
    kind_name = load_rig(rig_path).rig
    kind = kind_of(kind_name)
    plan_model, measures = kind.plan, kind.measures
    rig = read_yaml_mapping(rig_path)
    unknown = [name for name in sweep.objectives if name not in measures]
    if unknown or sweep.objectives[0] == sweep.objectives[1]:
        raise InputError(
            f"{path}: objectives: expected two different measures of {list(measures)}, "
            f"got {list(sweep.objectives)}"
        )
    plan_fields = set(plan_model.model_fields)
    unknown_plan = sorted(set(sweep.plan) - plan_fields)
    if unknown_plan:
        raise InputError(
            f"{path}: plan: unknown field {unknown_plan[0]!r}; expected some of "
            f"{sorted(plan_fields)}"
        )
    parameters = {}
    for name, values in sweep.parameters.items():
        _check_path(name, rig, plan_fields)
        parameters[name] = _values(name, values)
    count = int(np.prod([len(values) for values in parameters.values()]))
    if count > _MAX_POINTS:
        raise InputError(
            f"{path}: parameters: {count} design points; expected at most {_MAX_POINTS}"
        )
    points = [
        _point(index, dict(zip(parameters, combination, strict=True)), sweep, rig, kind, path)
        for index, combination in enumerate(itertools.product(*parameters.values()))
    ]
    return Sweep(path, sweep.name, kind_name, parameters, points, sweep.objectives, measures)
