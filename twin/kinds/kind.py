"""What a kind of rig is (:class:`RigKind`): its rig-file model, capture programs (each a frozen
:class:`ProgramSettings` model) and the hooks the commands call; what the hooks report
(:class:`Outcome`). The registry of kinds is :mod:`twin.kinds.registry`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from hwbridge.store import CaptureStore
from recon.errors import InputError
from twin.studies.sweep_file import SweepKind

__all__ = ["Outcome", "ProgramKind", "ProgramSettings", "RigKind"]


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
        As the store records it (the ``program`` of its rig attribute) and ``spectwin capture``
        names it.
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
