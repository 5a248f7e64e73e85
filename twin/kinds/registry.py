"""The rig registry: one :class:`RigKind` per kind of rig, looked up by the rig name its stores
record.

A capture store records its rig in ``attrs["rig"]["rig"]`` and the program that made it in
``attrs["rig"]["program"]``; a BTF store records the rig of the capture it was processed from in
``attrs["rig"]``. The commands find what to do with a store by that name here, never by testing
strings or types themselves. A new rig is a new :class:`RigKind` passed to :func:`register`
(see ARCHITECTURE.md, "Adding a rig").
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.errors import InputError
from twin.studies.sweep_file import SweepKind

__all__ = [
    "ProgramKind",
    "Outcome",
    "ProgramSettings",
    "RigKind",
    "btf_rig_kind",
    "capture_program",
    "capture_rig_kind",
    "config_rig_kind",
    "register",
    "rig_kind",
    "rig_kinds",
    "sweep_kind",
    "unregister",
]


class ProgramSettings(BaseModel):
    """The settings that define what a capture program captures (frozen; stored with the
    capture, so that a resumed capture is the same program): the session ``seed`` for all."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    seed: int = Field(0, ge=0, description="Session seed (noise of every frame).")


@dataclass(frozen=True)
class Outcome:
    """What a rig's calibrate, process or evaluate hook reports: a ``title`` and a ``summary``
    for the terminal, the JSON form where it differs (``as_json``), and ``failure``, a message
    when the work ran but its result is not usable as it stands."""

    title: str
    summary: dict[str, Any]
    as_json: dict[str, Any] | None = None
    failure: str | None = None


@dataclass(frozen=True)
class ProgramKind:
    """A capture program of a rig.

    Attributes
    ----------
    name
        As the store records it (``attrs["rig"]["program"]``) and ``spectwin capture`` names it.
    settings
        Its frozen settings model (a :class:`ProgramSettings`).
    build
        ``build(settings, fault_rate, dry_run)``: the program (with ``run`` and ``dry_run``,
        :class:`twin.devices.programs.ProgramCapture`) and notes for a dry run; every setting
        checked, nothing written.
    stored
        ``stored(capture)``: the settings of a capture store the program made.
    fault_rate
        Whether the program's simulated devices take injected faults.
    """

    name: str
    settings: type[ProgramSettings]
    build: Callable[[Any, float, bool], tuple[Any, dict[str, object]]]
    stored: Callable[[CaptureStore], ProgramSettings]
    fault_rate: bool = False


@dataclass(frozen=True)
class RigKind:
    """One kind of rig and everything the commands do with its stores.

    Attributes
    ----------
    name
        The rig's name in its YAML file (``rig:``) and in its stores.
    config
        The model of its YAML file (:mod:`twin.rigs.rig_config`).
    programs
        Its capture programs.
    calibrate
        ``calibrate(capture, out, options, show_progress)``: a calibration file from a
        calibration capture; ``out`` ``None`` for the default name.
    process
        ``process(capture, calibration, out, options, show_progress)``: a BTF store from a
        measurement run.
    evaluate
        ``evaluate(btf_path, spp, figure)``: the BTF against the twin's truth, with a figure when
        ``figure`` is given.
    estimate
        ``estimate(config)``: the capture time of one material (thesis 4.1.1, 10.2.2).
    sweep
        Its design-sweep models, check and measures (:mod:`twin.studies.sweep_file`).
    calibration_file, calibration_suffix
        The calibration's default file name, and the suffix its file must have (``None``: any).
    calibrate_options, process_options
        The optional settings of its calibrate and process hooks beyond the common ones (the
        command line refuses the others).
    passbands
        ``passbands(wavelengths_nm)``: the band passbands its BTF's bands stand for when rendered
        back (``None``: narrow bands).
    """

    name: str
    config: type[BaseModel]
    programs: tuple[ProgramKind, ...]
    calibrate: Callable[..., Outcome]
    process: Callable[..., Outcome]
    evaluate: Callable[..., Outcome]
    estimate: Callable[[Any], Outcome]
    sweep: SweepKind
    calibration_file: Path = Path("calibration.json")
    calibration_suffix: str | None = None
    calibrate_options: frozenset[str] = field(default_factory=frozenset)
    process_options: frozenset[str] = field(default_factory=frozenset)
    passbands: Callable[[Any], Any] = lambda wavelengths_nm: None

    def program(self, name: str) -> ProgramKind:
        """The capture program ``name``."""
        for program in self.programs:
            if program.name == name:
                return program
        known = [program.name for program in self.programs]
        raise InputError(
            f"program: the {self.name} has no capture program {name!r}; expected one of {known}"
        )


_KINDS: dict[str, RigKind] = {}


def register(kind: RigKind) -> RigKind:
    """Add ``kind`` to the registry (a kind of the same name is replaced); returns it."""
    _KINDS[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Remove the kind of rig ``name`` from the registry (nothing if it is not there)."""
    _KINDS.pop(name, None)


def rig_kinds() -> tuple[RigKind, ...]:
    """Every registered kind of rig, in the order registered."""
    _load_builtin()
    return tuple(_KINDS.values())


def rig_kind(name: object) -> RigKind:
    """The kind of rig named ``name``."""
    _load_builtin()
    if not isinstance(name, str) or name not in _KINDS:
        raise InputError(f"rig: expected one of {sorted(_KINDS)}, got {name!r}")
    return _KINDS[name]


def sweep_kind(name: str) -> SweepKind:
    """The sweep models and functions of the kind of rig named ``name``."""
    return rig_kind(name).sweep


def capture_rig_kind(capture: CaptureStore) -> RigKind:
    """The kind of rig that captured ``capture`` (its ``attrs["rig"]["rig"]``)."""
    rig = capture.attrs.get("rig")
    name = rig.get("rig") if isinstance(rig, Mapping) else None
    if name is None:
        raise InputError(
            f"{capture.path}: the store records no rig; expected a capture store of one of "
            f"{sorted(_names())}"
        )
    return rig_kind(name)


def capture_program(capture: CaptureStore) -> tuple[RigKind, ProgramKind]:
    """The kind of rig and the capture program that made ``capture``."""
    kind = capture_rig_kind(capture)
    return kind, kind.program(str(capture.attrs["rig"].get("program")))


def btf_rig_kind(btf: BTFStore | Path) -> RigKind:
    """The kind of rig whose capture a BTF store was processed from (its ``attrs["rig"]``)."""
    store = btf if isinstance(btf, BTFStore) else BTFStore.open(btf)
    name = store.attrs.get("rig")
    if name is None:
        raise InputError(
            f"{store.path}: a BTF store that no rig of spectwin processed (imported); expected "
            "one processed from a capture store"
        )
    return rig_kind(name)


def config_rig_kind(config: BaseModel) -> RigKind:
    """The kind of rig that a loaded rig file ``config`` describes (its ``rig`` field)."""
    return rig_kind(getattr(config, "rig", None))


def _names() -> list[str]:
    _load_builtin()
    return list(_KINDS)


@cache
def _load_builtin() -> None:
    """Register the built-in rigs on first use (a kind registered before keeps its place)."""
    from twin.kinds.builtin import BUILTIN_KINDS

    for kind in BUILTIN_KINDS:
        _KINDS.setdefault(kind.name, kind)
