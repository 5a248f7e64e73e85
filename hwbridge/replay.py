"""Replay of real captures: ingest a folder of frames into a capture store via a mapping file.

A mapping (YAML, :class:`Mapping`) lists regular expressions over the folder's relative paths
(``files``); every file that one of them matches in full is a frame (a TIFF). The named groups of
a pattern (:data:`GROUPS`) give the frame's ``camera``, ``kind``, plan ``step``, exposure
(``exposure_s`` or ``exposure_ms``), ``band_nm``, ``view_id`` and ``light_id``; a pattern may
also set ``kind``, ``camera``, ``light_id`` and ``view_id`` for all its files. Two more sources:

- ``sidecar``: the suffix of a JSON file beside every frame holding its record
  (:class:`hwbridge.export_frames.FrameSidecar`: timestamp, status, pose, lamp monitor);
  without it a frame's timestamp is its file's modification time;
- ``session``: a file of the folder (:class:`hwbridge.export_frames.SessionFile`) whose ``rig``,
  ``seed`` and ``plan`` the store takes: the rig's own attributes, so that the store processes
  as the rig's captures do. Every frame then names its ``step``, every step needs its frame,
  and what a name says must agree with its step.

Without a session the store's ``rig`` attribute is the mapping's ``rig``, a description
(:class:`hwbridge.schema.ReplayRigAttrs`, its program the mapping's name), and the plan is the
frames in the order of the patterns, then of their paths. The store's backend is ``replay``.

Everything is checked before anything is written (:func:`prepare_ingest`): the mapping, patterns
that match nothing, frames that cannot be read, frames of one camera of different sizes or bit
depths, missing fields, an existing store. Mappings shipped with spectwin live in
``hwbridge/mappings``: ``llanos2019``, and ``spectwin-gonio`` and ``spectwin-dome`` for the
folders that :mod:`hwbridge.export_frames` writes.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tifffile
import yaml
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from hwbridge.errors import InputError
from hwbridge.export_frames import FrameSidecar, SessionFile
from hwbridge.lock import StoreLock, require_new_store
from hwbridge.schema import (
    FRAME_KINDS,
    FrameKind,
    PlanStep,
    ReplayRigAttrs,
    RigAttrs,
    parse,
)
from hwbridge.store import CaptureStore, FrameRecord

__all__ = [
    "GROUPS",
    "MAPPING_DIR",
    "FilePattern",
    "Ingest",
    "LoadedMapping",
    "Mapping",
    "ingest",
    "load_mapping",
    "prepare_ingest",
]

MAPPING_DIR = Path(__file__).resolve().parent / "mappings"

GROUPS = ("camera", "kind", "step", "exposure_s", "exposure_ms", "band_nm", "view_id", "light_id")
"""The named groups a mapping's pattern may have."""

_COMPARED = ("kind", "exposure_s", "band_nm", "view_id", "light_id")  # a name against its step
_WRITE_BATCH = 64  # frames per write of the store


class _MappingModel(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class FilePattern(_MappingModel):
    """One entry of a mapping's ``files``: a pattern and what it sets for every file it matches."""

    pattern: str = Field(description="regular expression over a relative path, matched in full")
    kind: FrameKind | None = Field(None, description="frame kind; else the `kind` group")
    camera: str | None = Field(None, description="camera id; else the `camera` group")
    light_id: int | None = Field(None, description="light switched on")
    view_id: int | None = Field(None, description="view or stage position")

    @field_validator("pattern")
    @classmethod
    def _compiles(cls, pattern: str) -> str:
        try:
            groups = set(re.compile(pattern).groupindex)
        except re.error as error:
            raise ValueError(f"not a regular expression ({error})") from None
        unknown = sorted(groups - set(GROUPS))
        if unknown:
            raise ValueError(f"named groups {unknown}: expected groups among {list(GROUPS)}")
        return pattern

    @property
    def groups(self) -> set[str]:
        """The pattern's named groups."""
        return set(re.compile(self.pattern).groupindex)


class Mapping(_MappingModel):
    """A mapping file: how a folder of frames becomes a capture store (module docstring)."""

    source: str | None = Field(None, description="where the frames come from, in words")
    camera: str | None = Field(None, description="camera id of patterns that give none")
    rig: dict[str, Any] | None = Field(None, description="the rig described (`ReplayRigAttrs`)")
    session: str | None = Field(None, description="the folder's session file")
    sidecar: str | None = Field(None, description="suffix of every frame's JSON sidecar")
    files: tuple[FilePattern, ...] = Field(min_length=1, description="the patterns")

    @model_validator(mode="after")
    def _complete(self) -> Mapping:
        if self.rig is not None and self.session is not None:
            raise ValueError("rig and session: expected one (the session file holds the rig)")
        for number, entry in enumerate(self.files):
            where = f"files.{number}"
            if entry.kind is None and "kind" not in entry.groups:
                raise ValueError(f"{where}: no kind: expected a kind or a (?P<kind>...) group")
            if entry.camera is None and self.camera is None and "camera" not in entry.groups:
                raise ValueError(
                    f"{where}: no camera: expected a camera or a (?P<camera>...) group"
                )
            if self.session is not None and "step" not in entry.groups:
                raise ValueError(f"{where}: no (?P<step>...) group: expected one with a session")
        return self


@dataclass(frozen=True)
class LoadedMapping:
    """A mapping file read and validated: its ``name`` (the file's stem) and ``path``."""

    name: str
    path: Path
    spec: Mapping

    def replay_rig(self) -> ReplayRigAttrs:
        """The store's ``rig`` attribute that the mapping describes (used without a session)."""
        replay = {"rig": "replay", "program": self.name, **(self.spec.rig or {})}
        return parse(ReplayRigAttrs, replay, f"{self.path}: rig")


def load_mapping(name_or_path: str | Path) -> LoadedMapping:
    """A shipped mapping by name (``"llanos2019"``) or a mapping file by path, validated.

    Raises
    ------
    InputError
        No such file, not YAML, or not a :class:`Mapping` (an unknown key, a bad pattern, ...).
    """
    path = Path(name_or_path)
    if not path.suffix:
        path = MAPPING_DIR / f"{name_or_path}.yaml"
    if not path.is_file():
        known = sorted(p.stem for p in MAPPING_DIR.glob("*.yaml"))
        raise InputError(f"mapping: no file {path}; expected a path or one of {known}")
    try:
        data = yaml.safe_load(path.read_text())
    except (UnicodeDecodeError, yaml.YAMLError) as error:
        raise InputError(f"{path}: not a YAML file ({' '.join(str(error).split())})") from None
    loaded = LoadedMapping(path.stem, path, parse(Mapping, data, f"{path}"))
    if loaded.spec.session is None:
        loaded.replay_rig()  # a rig that does not fit is the mapping's error, found first
    return loaded


@dataclass(frozen=True)
class _Frame:
    """A matched file: its path in the folder, camera, step and plan settings its name and its
    pattern give, and the record of its sidecar."""

    file: str
    camera: str
    step: int | None
    named: dict[str, Any]
    record: FrameRecord | None


@dataclass(frozen=True)
class Ingest:
    """A folder's frames matched, read and checked against a mapping (:func:`prepare_ingest`);
    :meth:`write` writes the store."""

    source: Path
    store_path: Path
    mapping: str
    rig: dict[str, Any]
    seed: int
    software_version: str
    plan: list[dict[str, Any]]
    records: list[FrameRecord]
    cameras: dict[str, tuple[int, int]]
    monitor_samples: int
    frames: dict[str, int] = field(init=False)

    def __post_init__(self) -> None:
        counts: dict[str, int] = {}
        for step in self.plan:
            counts[step["camera"]] = counts.get(step["camera"], 0) + 1
        object.__setattr__(self, "frames", counts)

    def write(self, advance: Callable[[int], object] | None = None) -> CaptureStore:
        """Write the store: its frames (as uint16) and index, a batch at a time.

        Parameters
        ----------
        advance
            Called with the number of frames written after each batch.

        Returns
        -------
        CaptureStore
            The complete store.
        """
        with StoreLock.reserve(self.store_path) as lock:  # one writer per store (hwbridge.lock)
            store = CaptureStore.create(
                self.store_path,
                rig=self.rig,
                backend="replay",
                seed=self.seed,
                plan=self.plan,
                cameras=self.cameras,
                monitor_samples=self.monitor_samples,
                software_version=self.software_version,
            )
            lock.move_into()
            for start in range(0, len(self.plan), _WRITE_BATCH):
                steps = list(range(start, min(start + _WRITE_BATCH, len(self.plan))))
                frames = [_read_frame(self.source, self.plan[step]["file"]) for step in steps]
                store.write_frames(steps, [frame.astype(np.uint16) for frame in frames])
                store.write_index(steps, [self.records[step] for step in steps])
                store.mark_done(steps)
                if advance is not None:
                    advance(len(steps))
        return store


def _read_frame(source: Path, file: str) -> np.ndarray:
    try:
        frame = np.asarray(tifffile.imread(source / file))
    except (OSError, ValueError, KeyError, IndexError) as error:
        raise InputError(f"{source / file}: not a readable TIFF ({error})") from None
    if frame.ndim != 2 or frame.dtype not in (np.uint8, np.uint16):
        raise InputError(
            f"{source / file}: a {frame.dtype} frame of shape {frame.shape}: expected one "
            "monochrome or raw Bayer frame of 8 or 16 bit unsigned integers"
        )
    return frame


def _number(groups: dict[str, str], name: str, file: str) -> float | None:
    if name not in groups:
        return None
    try:
        return float(groups[name])
    except ValueError:
        raise InputError(f"{file}: {name} {groups[name]!r} is not a number") from None


def _named(entry: FilePattern, groups: dict[str, str], file: str) -> dict[str, Any]:
    """The plan settings a file's name and its pattern give."""
    named: dict[str, Any] = {}
    kind = entry.kind or groups.get("kind")
    if kind is not None:
        if kind not in FRAME_KINDS:
            raise InputError(f"{file}: kind {kind!r}: expected one of {FRAME_KINDS}")
        named["kind"] = kind
    exposure_ms = _number(groups, "exposure_ms", file)
    exposure_s = _number(groups, "exposure_s", file)
    if exposure_s is None and exposure_ms is not None:
        exposure_s = exposure_ms / 1000
    if exposure_s is not None:
        named["exposure_s"] = exposure_s
    band_nm = _number(groups, "band_nm", file)
    if band_nm is not None:
        named["band_nm"] = band_nm
    for name in ("light_id", "view_id"):
        value = getattr(entry, name)
        given = _number(groups, name, file)
        if given is not None:
            value = int(given)
        if value is not None:
            named[name] = value
    return named


def _sidecar(source: Path, file: str, suffix: str) -> FrameRecord:
    path = (source / file).with_suffix(suffix)
    if not path.is_file():
        raise InputError(f"{file}: no sidecar {path.name}: expected one beside every frame")
    try:
        data = json.loads(path.read_text())
    except (UnicodeDecodeError, ValueError) as error:
        raise InputError(f"{path}: not a JSON file ({error})") from None
    return parse(FrameSidecar, data, str(path)).record()


def _matched(source: Path, loaded: LoadedMapping) -> list[_Frame]:
    """Every file a pattern matches, in the order of the patterns and then of the paths."""
    spec = loaded.spec
    patterns = [re.compile(entry.pattern) for entry in spec.files]
    found: list[list[_Frame]] = [[] for _ in patterns]
    for path in sorted(source.rglob("*")):
        file = path.relative_to(source).as_posix()
        matches = [(n, match) for n, p in enumerate(patterns) if (match := p.fullmatch(file))]
        if not matches or not path.is_file():
            continue
        if len(matches) > 1:
            numbers = [number for number, _ in matches]
            raise InputError(f"{loaded.path}: {file} matches files {numbers}: expected one")
        ((number, match),) = matches
        groups = {name: text for name, text in match.groupdict().items() if text is not None}
        entry = spec.files[number]
        step = _number(groups, "step", file)
        found[number].append(
            _Frame(
                file=file,
                camera=str(groups.get("camera") or entry.camera or spec.camera),
                step=None if step is None else int(step),
                named=_named(entry, groups, file),
                record=None if spec.sidecar is None else _sidecar(source, file, spec.sidecar),
            )
        )
    for number, frames in enumerate(found):
        if not frames:
            pattern = spec.files[number].pattern
            raise InputError(
                f"{loaded.path}: files.{number} pattern {pattern} matches no file in {source}"
            )
    return [frame for frames in found for frame in frames]


def _record(frame: _Frame, settings: PlanStep, source: Path) -> FrameRecord:
    """The frame's record: its sidecar's, which must agree with its step, or the step's."""
    if frame.record is None:
        return FrameRecord(
            kind=settings.kind,
            exposure_s=settings.exposure_s,
            timestamp=(source / frame.file).stat().st_mtime,
            light_id=settings.light_id,
            view_id=settings.view_id,
            band_nm=math.nan if settings.band_nm is None else settings.band_nm,
        )
    for name in ("kind", "exposure_s"):
        if getattr(frame.record, name) != getattr(settings, name):
            raise InputError(
                f"{frame.file}: its sidecar's {name} {getattr(frame.record, name)!r} differs "
                f"from its step's {getattr(settings, name)!r}"
            )
    return frame.record


def _session_plan(
    source: Path, session: SessionFile, frames: list[_Frame], names: set[str]
) -> tuple[list[_Frame], list[PlanStep]]:
    """The frames in the order of the session's plan, each checked against its step; ``names``:
    the fields the patterns have groups for (a step's value of one must be in the name)."""
    by_step: dict[int, _Frame] = {}
    for frame in frames:
        step = frame.step if frame.step is not None else -1
        if not 0 <= step < len(session.plan):
            raise InputError(f"{frame.file}: step {step}: expected 0..{len(session.plan) - 1}")
        if step in by_step:
            raise InputError(f"{frame.file} and {by_step[step].file}: both frames of step {step}")
        settings = session.plan[step]
        if frame.camera != settings.camera:
            raise InputError(
                f"{frame.file}: camera {frame.camera!r}, but step {step} is camera "
                f"{settings.camera!r}"
            )
        for name in _COMPARED:
            value = getattr(settings, name)
            stated = name in settings.model_fields_set and value is not None
            if name in frame.named and not _same(frame.named[name], value):
                raise InputError(
                    f"{frame.file}: {name} {frame.named[name]!r} in its name, but step {step} "
                    f"has {value!r}"
                )
            if name not in frame.named and stated and name in names:
                raise InputError(f"{frame.file}: no {name} in its name; step {step} has {value!r}")
        by_step[step] = frame
    missing = sorted(set(range(len(session.plan))) - set(by_step))
    if missing:
        raise InputError(
            f"{source}: {len(missing)} of {len(session.plan)} steps have no frame (first step "
            f"{missing[0]}): expected a frame for every step of the session"
        )
    return [by_step[step] for step in range(len(session.plan))], list(session.plan)


def _same(named: object, value: object) -> bool:
    """A value in a name is the step's (a float to within its text's rounding)."""
    if isinstance(named, float) and isinstance(value, float):
        return math.isclose(named, value, rel_tol=1e-9)
    return named == value


def _folder_plan(frames: list[_Frame]) -> list[PlanStep]:
    """A plan of the frames as the folder gives them."""
    plan = []
    for frame in frames:
        exposure_s = frame.named.get("exposure_s")
        if exposure_s is None and frame.record is not None:
            exposure_s = frame.record.exposure_s
        if exposure_s is None:
            raise InputError(
                f"{frame.file}: no exposure: expected an exposure_ms or exposure_s group, or a "
                "sidecar"
            )
        settings = {**frame.named, "camera": frame.camera, "exposure_s": exposure_s}
        plan.append(parse(PlanStep, settings, frame.file))
    return plan


def _read_session(source: Path, name: str) -> SessionFile:
    path = source / name
    if not path.is_file():
        raise InputError(
            f"{path}: no session file: expected the one written after every frame (an export "
            "that did not finish has none)"
        )
    try:
        data = json.loads(path.read_text())
    except (UnicodeDecodeError, ValueError) as error:
        raise InputError(f"{path}: not a JSON file ({error})") from None
    session = parse(SessionFile, data, str(path))
    parse(RigAttrs, session.rig, f"{path}: rig")
    return session


def _frame_shapes(source: Path, frames: list[_Frame]) -> dict[str, tuple[int, int]]:
    """Every camera's frame shape; every frame is read, and those of a camera must be alike."""
    first: dict[str, tuple[str, np.ndarray]] = {}
    for frame in frames:
        pixels = _read_frame(source, frame.file)
        seen, reference = first.setdefault(frame.camera, (frame.file, pixels))
        if (pixels.shape, pixels.dtype) != (reference.shape, reference.dtype):
            raise InputError(
                f"{frame.file}: {pixels.dtype} {pixels.shape}, but {seen} is {reference.dtype} "
                f"{reference.shape}: expected the frames of camera {frame.camera!r} alike"
            )
    return {camera: (int(a.shape[0]), int(a.shape[1])) for camera, (_, a) in first.items()}


def prepare_ingest(source: str | Path, mapping: str | Path, store_path: str | Path) -> Ingest:
    """Match, read and check the frames of ``source`` for a new store at ``store_path``;
    nothing is written.

    Parameters
    ----------
    source
        The folder of frames.
    mapping
        A shipped mapping's name or a mapping file (:func:`load_mapping`).
    store_path
        The capture store to write; it must not exist.

    Returns
    -------
    Ingest
        The store's rig, seed, plan, records and cameras; :meth:`Ingest.write` writes it.

    Raises
    ------
    InputError
        On the first problem found (module docstring).
    """
    source, store_path = Path(source), Path(store_path)
    if not source.is_dir():
        raise InputError(f"source: {source} is not a folder")
    loaded = load_mapping(mapping)
    require_new_store(store_path)
    spec = loaded.spec
    frames = _matched(source, loaded)
    if spec.session is not None:
        session = _read_session(source, spec.session)
        names = set().union(*(entry.groups for entry in spec.files))
        if "exposure_ms" in names:
            names.add("exposure_s")
        frames, plan = _session_plan(source, session, frames, names)
        rig, seed, software_version = session.rig, session.seed, session.software_version
    else:
        plan = _folder_plan(frames)
        rig = loaded.replay_rig().stored()
        seed, software_version = 0, "0"
    records = [
        _record(frame, settings, source) for frame, settings in zip(frames, plan, strict=True)
    ]
    cameras = _frame_shapes(source, frames)
    if spec.session is not None:
        for camera, shape in cameras.items():
            expected = session.cameras.get(camera)
            if expected is not None and tuple(expected) != shape:
                raise InputError(
                    f"{source}: frames of camera {camera!r} are {shape}; the session says "
                    f"{tuple(expected)}"
                )
    monitors = {len(r.lamp_monitor) for r in records if r.lamp_monitor is not None}
    if len(monitors) > 1:
        raise InputError(
            f"{source}: lamp monitor spectra of {sorted(monitors)} samples: expected one length"
        )
    steps = [
        settings.model_dump(mode="json", exclude_unset=True) | {"file": frame.file}
        for frame, settings in zip(frames, plan, strict=True)
    ]
    return Ingest(
        source=source,
        store_path=store_path,
        mapping=loaded.name,
        rig=rig,
        seed=seed,
        software_version=software_version,
        plan=steps,
        records=records,
        cameras=cameras,
        monitor_samples=monitors.pop() if monitors else 0,
    )


def ingest(source: str | Path, mapping: str | Path, store_path: str | Path) -> CaptureStore:
    """Read every mapped frame of ``source`` into a new capture store at ``store_path``
    (:func:`prepare_ingest`, then :meth:`Ingest.write`)."""
    return prepare_ingest(source, mapping, store_path).write()
