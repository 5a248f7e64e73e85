"""The capture store: raw frames and their metadata in Zarr v3, written resumably.

Layout of ``<name>.capture.zarr`` (ARCHITECTURE.md, "Stores"):

- attributes (:class:`hwbridge.schema.CaptureAttrs`): ``schema_version``, ``store_id`` (the
  store's random identity), ``sealed`` (digests of what defines its content), ``rig`` (the rig
  and the program that captured, a :class:`~hwbridge.schema.RigAttrs` of the rig's kind),
  ``backend`` (``sim``, ``real``, ``replay``), ``seed``, ``software_version``, ``plan`` (one
  :class:`~hwbridge.schema.PlanStep` per step), ``complete``;
- ``frames/<camera_id>``: uint16 ``(N, H, W)`` raw frames, one chunk per frame;
- ``index/<camera_id>/<field>``: per frame ``kind``, ``light_id``, ``view_id``, ``band_nm``,
  ``exposure_s``, ``timestamp``, ``status``, ``pose`` (6 numbers), ``seal`` (the seal of the
  frame's chunk) and ``lamp_monitor`` (the monitor spectrum, when the rig has one);
- ``progress``: one flag per plan step, set only after the step's frame and index are written.

A dome capture (thesis 10.2-10.4) uses the same layout with one group per camera (the RGB
cameras of the arc and the spectral camera); :mod:`hwbridge.dome_layout` says what its index
fields and its ``rig`` attribute (camera, LED and stage geometry, the targets) hold.

The attributes are read through the models of :mod:`hwbridge.schema` (:attr:`CaptureStore.
metadata`, :meth:`CaptureStore.rig_attrs`); :meth:`CaptureStore.open` refuses a store of another
``schema_version`` (or none) in one line.

A simulated capture holds :data:`INDEX_CHUNK_FRAMES` frames per chunk of the index and the
flags and compresses its frames with Zstd level 1 (a noisy 256 px frame: 0.36 ms to 84 % of its
size, against 1.6 ms to 75 % at Zstd's default level 3); a real or replayed one keeps one frame
per chunk of the index and the default level (its frames cannot be taken again, so a damaged
chunk must cost one frame, and a real rig takes a minute per direction pair, beside which
writing chunks costs nothing).

Frames have one chunk per frame, so writers that own disjoint sets of steps write disjoint
chunks: the workers of a distributed capture (``twin.devices.cluster``) write their frames
straight into one store. The index and the progress flags are written by one writer only (the
session, or a distributed capture's coordinator, from the records its workers return), in
batches (:meth:`CaptureStore.write_index`, :meth:`CaptureStore.mark_done`): Zarr spends about a
millisecond on every chunk it writes, which one chunk per frame and field made the largest cost
of a small simulated frame. Stores made before hold the index and the flags in one chunk per
frame (or ``kind`` and ``status`` in one chunk per camera); they are read and resumed alike.
The stores open their groups through :mod:`hwbridge.local_store` (small files read and written
without a thread hand-over), and the index fields and flags carry a checksum but no Zstd (a few
bytes per chunk do not compress); stores made before keep Zstd there and read alike.

A step's frame slot is fixed by the plan, so redoing a step after a crash overwrites the same
slot: an interrupted session resumes without losing or duplicating a frame, and ``complete``
turns true only when every step is done.

Integrity (:mod:`hwbridge.integrity`): every array ends its codec chain with a CRC-32C checksum,
so a chunk altered on disk raises on read, and every frame's chunk is sealed to its place and
the store (:class:`~hwbridge.integrity.Seal`; the index writer records the seal, so the workers
of a distributed capture write only their frames): a frame chunk swapped, moved, copied from
another store or of another shape is reported and refused like a corrupt one. The settings
that define the store (``rig``, ``backend``, ``seed``, ``software_version``, ``plan``) and
the shape, chunks and dtype of every array are sealed at creation: :meth:`CaptureStore.open`
refuses a store where any differs, naming them. :meth:`CaptureStore.check` checks the progress
record against the chunks: a step flagged done whose frame or index chunk is missing (Zarr would
read the fill value) or corrupt is reported by camera, step and chunk key. :meth:`CaptureStore.open`
refuses a store whose metadata (``zarr.json`` files) is missing or unreadable, naming the file,
and :meth:`CaptureStore.read_frames` refuses to return a missing or corrupt frame. Before a
session resumes, :meth:`CaptureStore.prepare_resume` flags the damaged steps of a simulated
capture pending again (they are taken again, identically) and refuses to resume a damaged real
or replayed capture, which cannot take its frames again. Stores made before seals (schema
version 1) are refused, naming their version.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import zarr

from hwbridge.errors import DamagedDataError, InputError, Remedy
from hwbridge.integrity import (
    SEAL_DTYPE,
    ChunkChecker,
    ChunkProblem,
    IntegrityReport,
    Seal,
    array_at,
    checksum_only,
    checksum_state,
    checksummed_compressors,
    chunk_key,
    group_at,
    metadata_problem,
    read_flags,
    seal_problem,
    sealed_content,
    stored_arrays,
    with_empty_chunks,
)
from hwbridge.local_store import open_local_group
from hwbridge.schema import (
    FRAME_KINDS,
    NO_LIGHT,
    NO_VIEW,
    SCHEMA_VERSION,
    CaptureAttrs,
    RigAttrs,
    parse,
    refuse_other_version,
)

__all__ = ["INDEX_CHUNK_FRAMES", "CaptureStore", "FrameRecord"]

Rig = TypeVar("Rig", bound=RigAttrs)

INDEX_CHUNK_FRAMES = 1024
"""Frames (steps) per chunk of the index fields and the progress flags of a simulated capture."""
_SIMULATED_FRAME_LEVEL = 1  # Zstd level of simulated frames (real ones: Zstd's default, 3)

_STRING_FIELDS = ("kind", "status")
_NUMERIC_FIELDS = {
    "light_id": "int32",
    "view_id": "int32",
    "band_nm": "float32",
    "exposure_s": "float64",
    "timestamp": "float64",
}
# Index fields every frame writes with a value other than the fill value: a step flagged done
# must have their chunks (the others hold the fill value legitimately, e.g. no light for a dark).
_REQUIRED_FIELDS = ("kind", "status", "exposure_s", "seal")
_INDEX_FIELDS = (*_STRING_FIELDS, *_NUMERIC_FIELDS, "pose", "seal")
# The attributes that define a store's content, sealed at creation (all but the progress).
_SEALED_ATTRS = ("schema_version", "rig", "backend", "seed", "software_version", "plan")


@dataclass(frozen=True)
class FrameRecord:
    """Metadata of one frame."""

    kind: str
    exposure_s: float
    timestamp: float
    light_id: int = NO_LIGHT
    view_id: int = NO_VIEW
    band_nm: float = float("nan")
    status: str = "ok"
    pose: tuple[float, ...] = (np.nan,) * 6
    lamp_monitor: np.ndarray | None = field(default=None)

    def __post_init__(self) -> None:
        if self.kind not in FRAME_KINDS:
            raise InputError(f"kind: expected one of {FRAME_KINDS}, got {self.kind!r}")
        if not np.isfinite(self.exposure_s) or self.exposure_s < 0:
            raise InputError(f"exposure_s: expected a non-negative time, got {self.exposure_s}")
        if len(self.pose) != 6:
            raise InputError(f"pose: expected 6 numbers, got {len(self.pose)}")


class CaptureStore:
    """A capture store on disk; create it with :meth:`create`, reopen it with :meth:`open`."""

    def __init__(self, group: zarr.Group, path: Path):
        self._group = group
        self.path = path
        self._cameras: list[str] = [step["camera"] for step in self.attrs["plan"]]
        counts: dict[str, int] = {}
        self._slots: list[int] = []
        self._steps: dict[str, list[int]] = {}
        for step, camera in enumerate(self._cameras):
            self._slots.append(counts.get(camera, 0))
            counts[camera] = counts.get(camera, 0) + 1
            self._steps.setdefault(camera, []).append(step)
        self._seal = Seal(str(group.attrs.get("store_id")))
        self.recaptured: list[ChunkProblem] = []
        """Damaged chunks of steps that :meth:`prepare_resume` flagged pending again."""
        # Steps this writer has not seen done. Reading the progress flags touches one chunk per
        # step, so mark_done consults this set and re-reads the flags only when it runs empty.
        self._unseen: set[int] | None = None
        # The index fields of a complete store as read, per (camera, field): a calibration
        # selects frames by kind and band a dozen times, and a real capture's index holds one
        # chunk per frame and field, so each read touches every frame's chunk.
        self._complete_index: dict[tuple[str, str], np.ndarray] = {}
        # The arrays as opened, by key (their metadata read once; chunks are read on access).
        self._arrays: dict[str, zarr.Array[Any]] = {}

    @classmethod
    def create(
        cls,
        path: str | Path,
        *,
        rig: RigAttrs | Mapping[str, Any],
        backend: str,
        seed: int,
        plan: Sequence[Mapping[str, Any]],
        cameras: dict[str, tuple[int, int]],
        monitor_samples: int = 0,
        software_version: str = "0",
    ) -> CaptureStore:
        """A new, empty store for ``plan`` (steps as :class:`~hwbridge.schema.PlanStep` takes
        them, each naming its ``camera``) and ``rig`` (a :class:`~hwbridge.schema.RigAttrs` of
        the rig's kind, or as it records itself); never overwrites."""
        path = Path(path)
        if path.exists():
            raise InputError(
                f"{path} exists: expected a new store (nothing was overwritten)",
                remedy=Remedy.resume_or_rename,
            )
        if backend not in ("sim", "real", "replay"):
            raise InputError(f"backend: expected 'sim', 'real' or 'replay', got {backend!r}")
        if not plan:
            raise InputError("plan: expected at least one step")
        store_id = Seal.new_id()
        attrs = parse(
            CaptureAttrs,
            {
                "schema_version": SCHEMA_VERSION,
                "store_id": store_id,
                "sealed": {},
                "rig": rig.stored() if isinstance(rig, RigAttrs) else dict(rig),
                "backend": backend,
                "seed": seed,
                "software_version": software_version,
                "plan": plan,
                "complete": False,
            },
            f"{path}: capture store attributes",
        )
        unknown = sorted({step.camera for step in attrs.plan} - set(cameras))
        if unknown:
            raise InputError(
                f"plan: steps name cameras {unknown} that are not among {sorted(cameras)}"
            )
        # Build the store beside its final name and rename it into place when its plan and
        # progress exist: a session killed while creating leaves no half-made store behind.
        building = path.with_name(f".{path.name}.creating")
        shutil.rmtree(building, ignore_errors=True)
        group = open_local_group(building, mode="w-", zarr_format=3)
        per_chunk = INDEX_CHUNK_FRAMES if backend == "sim" else 1
        frame_level = _SIMULATED_FRAME_LEVEL if backend == "sim" else 0
        for camera, (height, width) in cameras.items():
            count = sum(step.camera == camera for step in attrs.plan)
            group.create_array(
                f"frames/{camera}",
                shape=(count, height, width),
                chunks=(1, height, width),
                dtype="uint16",
                compressors=checksummed_compressors(frame_level),
            )
            index = f"index/{camera}"
            block = min(count, per_chunk)
            for name in _STRING_FIELDS:
                group.create_array(
                    f"{index}/{name}",
                    shape=(count,),
                    chunks=(block,),
                    dtype=str,
                    fill_value="",
                    compressors=checksum_only(),
                )
            for name, dtype in _NUMERIC_FIELDS.items():
                fill = -1 if dtype.startswith("int") else np.nan
                group.create_array(
                    f"{index}/{name}",
                    shape=(count,),
                    chunks=(block,),
                    dtype=dtype,
                    fill_value=fill,
                    compressors=checksum_only(),
                )
            group.create_array(
                f"{index}/seal",
                shape=(count,),
                chunks=(block,),
                dtype=SEAL_DTYPE,
                fill_value=0,
                compressors=checksum_only(),
            )
            group.create_array(
                f"{index}/pose",
                shape=(count, 6),
                chunks=(block, 6),
                dtype="float64",
                fill_value=np.nan,
                compressors=checksum_only(),
            )
            if monitor_samples:
                group.create_array(
                    f"{index}/lamp_monitor",
                    shape=(count, monitor_samples),
                    chunks=(block, monitor_samples),
                    dtype="float32",
                    fill_value=np.nan,
                    compressors=checksum_only(),
                )
        group.create_array(
            "progress",
            shape=(len(plan),),
            chunks=(min(len(plan), per_chunk),),
            dtype="bool",
            fill_value=False,
            compressors=checksum_only(),
        )
        # The attributes last and in one write: the plan of a full campaign is tens of MB of
        # JSON, which Zarr writes out again for every attribute set. A plan step keeps the
        # settings it was given, no others. What defines the store's content is sealed.
        stored = attrs.model_dump(mode="json", exclude_unset=True)
        content = {name: stored[name] for name in _SEALED_ATTRS}
        stored["sealed"] = Seal(store_id).settings(
            sealed_content(content, stored_arrays(group).values())
        )
        group.update_attributes(stored)
        building.rename(path)
        return cls(open_local_group(path, mode="r+"), path)

    @classmethod
    def open(cls, path: str | Path) -> CaptureStore:
        path = Path(path)
        if not path.exists():
            raise InputError(f"{path} does not exist: expected a capture store")
        if not path.is_dir():
            raise InputError(f"{path} is a file: expected a capture store (a folder)")
        root_problem = metadata_problem(path, "")
        if root_problem and any((path / name).is_dir() for name in ("frames", "index", "progress")):
            raise DamagedDataError(
                f"damaged capture store: {root_problem}: the root metadata (plan, seed, backend) "
                "is gone, so no frame can be placed; restore the store from a copy or capture again"
            )
        try:
            group = open_local_group(path, mode="r+")
        except (OSError, ValueError) as error:
            raise InputError(f"{path} is not a capture store (not a Zarr group: {error})") from None
        if "plan" not in group.attrs:
            raise InputError(f"{path} is not a capture store (no plan or progress)")
        refuse_other_version(
            path,
            "a capture store",
            "schema version",
            group.attrs.get("schema_version"),
            SCHEMA_VERSION,
        )
        stored: dict[str, Any] = dict(group.attrs)
        cameras = sorted({str(step.get("camera")) for step in stored["plan"]})
        for node in _layout(cameras):
            problem = metadata_problem(path, node)
            # lamp_monitor exists only where the rig has a monitor: missing is fine, unless its
            # chunks are there without their metadata.
            if problem and (not node.endswith("/lamp_monitor") or (path / node).is_dir()):
                raise DamagedDataError(
                    f"damaged capture store: {problem} (the metadata of {node}); restore the "
                    "store from a copy or capture again"
                )
        sealed = stored.get("sealed")
        problem = seal_problem(
            Seal(str(stored.get("store_id"))),
            sealed if isinstance(sealed, dict) else {},
            {name: stored.get(name) for name in _SEALED_ATTRS},
            stored_arrays(group).values(),
        )
        if problem:
            raise DamagedDataError(
                f"{path}: damaged capture store: {problem}; restore the store from a copy or "
                "capture again"
            )
        return cls(group, path)

    # -- writing -------------------------------------------------------------------------------

    def write_frame(self, step: int, frame: np.ndarray, record: FrameRecord) -> None:
        """Write the frame and index of ``step`` into its slot (idempotent for a redone step)."""
        self.write_frames([step], [frame])
        self.write_index([step], [record])

    def write_frames(self, steps: Sequence[int], frames: Sequence[np.ndarray]) -> None:
        """Write the frames of ``steps`` into their slots (idempotent for redone steps); a run of
        consecutive slots of one camera is one Zarr call, which writes its chunks concurrently.
        Frames have one chunk each, so writers of disjoint steps never share a chunk."""
        for camera, positions, slots in self._runs(steps):
            array = self.frames(camera)
            stack = np.stack([np.asarray(frames[position]) for position in positions])
            if stack.shape[1:] != array.shape[1:] or stack.dtype != np.uint16:
                raise InputError(
                    f"frame: expected uint16 {array.shape[1:]} for camera {camera!r}, got "
                    f"{stack.dtype} {stack.shape[1:]}"
                )
            with_empty_chunks(array)[slots] = stack

    def write_index(self, steps: Sequence[int], records: Sequence[FrameRecord]) -> None:
        """Write the index of ``steps`` (one Zarr call per field and run of consecutive slots).
        One writer only: a chunk holds the index of :data:`INDEX_CHUNK_FRAMES` frames."""
        self._complete_index.clear()
        for camera, positions, slots in self._runs(steps):
            index = f"index/{camera}"
            chosen = [records[position] for position in positions]
            for name in (*_STRING_FIELDS, *_NUMERIC_FIELDS):
                values = np.array([getattr(record, name) for record in chosen])
                self._array(f"{index}/{name}")[slots] = values
            poses = np.array([record.pose for record in chosen], np.float64)
            self._array(f"{index}/pose")[slots] = poses
            frames = self.frames(camera)
            self._array(f"{index}/seal")[slots] = np.array(
                [
                    self._seal.chunk_on_disk(self.path, frames, (slot, 0, 0))
                    for slot in range(slots.start, slots.stop)
                ],
                np.uint64,
            )
            monitored = [i for i, record in enumerate(chosen) if record.lamp_monitor is not None]
            if not monitored:
                continue
            try:
                lamp_monitor = self._array(f"{index}/lamp_monitor")
            except KeyError:
                raise InputError(
                    "lamp_monitor: this store was created without monitor samples"
                ) from None
            spectra = np.array([chosen[i].lamp_monitor for i in monitored], np.float32)
            if len(monitored) == slots.stop - slots.start:
                lamp_monitor[slots] = spectra
            else:
                lamp_monitor.oindex[np.array([slots.start + i for i in monitored])] = spectra

    def _runs(self, steps: Sequence[int]) -> Iterator[tuple[str, list[int], slice]]:
        """``(camera, positions in steps, slots)`` per camera and run of consecutive slots."""
        by_camera: dict[str, list[tuple[int, int]]] = {}
        for position, step in enumerate(steps):
            camera, slot = self._camera_and_slot(int(step))
            by_camera.setdefault(camera, []).append((slot, position))
        for camera, pairs in by_camera.items():
            pairs.sort()
            start = 0
            for end in range(1, len(pairs) + 1):
                if end == len(pairs) or pairs[end][0] != pairs[end - 1][0] + 1:
                    run = pairs[start:end]
                    slots = slice(run[0][0], run[-1][0] + 1)
                    yield camera, [position for _, position in run], slots
                    start = end

    def mark_done(self, steps: int | Sequence[int], *, check_complete: bool = True) -> None:
        """Flag ``steps`` done (one writer only); when every step is, the store is marked
        complete.

        Parameters
        ----------
        steps
            Plan steps (or one step) whose frames and index are written.
        check_complete
            ``False`` leaves the store's attributes to the caller (:meth:`refresh_complete`).
        """
        steps = [int(steps)] if isinstance(steps, int | np.integer) else [int(s) for s in steps]
        for step in steps:
            self._camera_and_slot(step)
        flags = np.ones(len(steps), bool)
        ordered = sorted(steps)
        progress = self._array("progress")
        if ordered and ordered == list(range(ordered[0], ordered[-1] + 1)):
            progress[ordered[0] : ordered[-1] + 1] = flags
        elif steps:
            progress.oindex[np.array(steps)] = flags
        if not check_complete:
            return
        if self._unseen is None:
            self._unseen = set(self.pending_steps())
        self._unseen.difference_update(steps)
        if not self._unseen:
            self._unseen = set(self.pending_steps())
            if not self._unseen:
                self._group.attrs["complete"] = True

    def refresh_complete(self) -> bool:
        """Set ``complete`` from the progress flags on disk (after the workers of a distributed
        capture are done) and return it."""
        self._unseen = set(self.pending_steps())
        self._group.attrs["complete"] = not self._unseen
        return not self._unseen

    # -- reading -------------------------------------------------------------------------------

    def pending_steps(self) -> list[int]:
        pending: list[int] = np.flatnonzero(~self._flags()).tolist()
        return pending

    @property
    def complete(self) -> bool:
        return bool(self._group.attrs["complete"])

    @property
    def attrs(self) -> dict[str, Any]:
        """The attributes as stored (JSON); read them through :attr:`metadata` and
        :meth:`rig_attrs`."""
        return dict(self._group.attrs)

    @cached_property
    def metadata(self) -> CaptureAttrs:
        """The attributes, validated, as they were when first asked for (the plan of a full
        campaign takes a second to validate); :attr:`complete` reads the flag as it is now."""
        return parse(CaptureAttrs, self.attrs, f"{self.path}: capture store attributes")

    def rig_attrs(self, model: type[Rig]) -> Rig:
        """The ``rig`` attribute validated as ``model`` (the rig's kind's model, or
        :class:`~hwbridge.schema.RigAttrs` for the rig's name and program); a rig it does not
        fit raises :class:`~hwbridge.errors.InputError`, naming the field."""
        return parse(model, self._group.attrs.get("rig"), f"{self.path}: rig attribute")

    def frames(self, camera: str) -> zarr.Array[Any]:
        return self._array(f"frames/{camera}")

    def index(self, camera: str, fields: Sequence[str] | None = None) -> dict[str, np.ndarray]:
        """The index of ``camera``'s frames: every field, or only ``fields`` (each field is one
        chunk per frame, so reading fewer is proportionally faster)."""
        if fields is None:
            names = list(group_at(self._group, f"index/{camera}").array_keys())
        else:
            names = list(fields)
        return {name: self._index_field(camera, name) for name in names}

    def _index_field(self, camera: str, name: str) -> np.ndarray:
        """One field of ``camera``'s index; read once while the store is complete (a copy each
        time: the caller may change it)."""
        kept = self._complete_index.get((camera, name))
        if kept is None:
            kept = self._read(self._array(f"index/{camera}/{name}"))
            if not self.complete:
                return kept
            self._complete_index[camera, name] = kept
        return kept.copy()

    def read_frames(self, camera: str, slots: Sequence[int] | np.ndarray) -> np.ndarray:
        """The frames ``(n, H, W)`` of ``camera`` at ``slots``; a frame whose chunk is missing
        (it would read as zeros), corrupt or sealed elsewhere (another frame's, another
        store's) raises :class:`~hwbridge.errors.DamagedDataError` naming camera, step and
        chunk key."""
        frames = self.frames(camera)
        stack = np.empty((len(slots), *frames.shape[1:]), dtype=frames.dtype)
        checker = ChunkChecker(self.path, seal=self._seal)
        chosen = np.asarray(slots, np.int64).reshape(-1)
        seals = self._seals(camera, chosen) if chosen.size else chosen
        for position, slot in enumerate(chosen.tolist()):
            coords = (slot, 0, 0)
            name = self._step_name(self._steps[camera][slot])
            found = checker.check(frames, coords, int(seals[position]))
            if found:
                problem = ChunkProblem(name, chunk_key(frames, coords), *found)
                raise DamagedDataError(f"{self.path}: damaged capture store: {problem}")
            try:
                stack[position] = frames[int(slot)]
            except (ValueError, RuntimeError) as error:  # checksum or decompression
                raise DamagedDataError(
                    f"{self.path}: damaged capture store: {name}: {chunk_key(frames, coords)} "
                    f"is corrupt ({' '.join(str(error).split())[:120]})"
                ) from None
        return stack

    # -- integrity -----------------------------------------------------------------------------

    def check(self, *, verify: bool = True) -> IntegrityReport:
        """Check every step flagged done against its chunks (see :mod:`hwbridge.integrity`).

        Parameters
        ----------
        verify
            Check the chunks' checksums too (reads every frame once, without decompressing);
            ``False``: only that the chunk files exist.

        Returns
        -------
        IntegrityReport
            Pending steps, missing and corrupt chunks by camera, step and chunk key, whether
            the store has checksums, and its seed, program and backend.
        """
        checker = ChunkChecker(self.path, verify=verify, seal=self._seal)
        progress = array_at(self._group, "progress")
        values, problems = read_flags(checker, progress, self._step_name)
        flags = values.astype(bool)
        arrays = {camera: self._unit_arrays(camera) for camera in self._steps}
        seals = {camera: self._seals(camera) for camera in self._steps}
        # Per camera and array: the array, whether a done step needs its chunk, frames per chunk
        # and the chunk's coordinates after the first (looked up once: Zarr's are slow).
        layout = {
            camera: [
                (array, array.path, required, array.chunks[0], (0,) * (array.ndim - 1))
                for array, required in listed
            ]
            for camera, listed in arrays.items()
        }
        outcomes: dict[tuple[str, int], tuple[str, str] | None] = {}
        units: dict[tuple[str, int], tuple[zarr.Array[Any], tuple[str, str], list[int]]] = {}
        for step in np.flatnonzero(flags).tolist():
            camera, slot = self._camera_and_slot(step)
            for position, (array, path, required, rows, rest) in enumerate(layout[camera]):
                place = (path, slot // rows)
                if place not in outcomes:  # a chunk shared by frames is read once
                    sealed = int(seals[camera][slot]) if position == 0 else None  # the frame
                    outcome = checker.check(array, (place[1], *rest), sealed)
                    if outcome is not None and outcome[0] == "missing" and not required:
                        outcome = None
                    outcomes[place] = outcome
                found = outcomes[place]
                if found is not None:
                    units.setdefault(place, (array, found, []))[2].append(step)
        for (_, chunk), (array, (problem, detail), steps) in units.items():
            key = chunk_key(array, (chunk, *(0,) * (array.ndim - 1)))
            problems.append(
                ChunkProblem(self._step_name(steps[0]), key, problem, detail, tuple(steps))
            )
        problems.sort(key=lambda problem: (min(problem.units, default=-1), problem.key))
        every_array = [progress, *(a for listed in arrays.values() for a, _ in listed)]
        rig = self._group.attrs.get("rig") or {}
        return IntegrityReport(
            path=self.path,
            kind="capture",
            unit="step",
            total=len(self._cameras),
            pending=np.flatnonzero(~flags).tolist(),
            complete_flag=bool(self._group.attrs.get("complete", False)),
            problems=problems,
            checksums=checksum_state(checker.checksums(array) for array in every_array),
            verified=verify,
            provenance={
                "backend": self._group.attrs.get("backend"),
                "program": rig.get("program") if isinstance(rig, dict) else None,
                "seed": self._group.attrs.get("seed"),
            },
        )

    def prepare_resume(self) -> list[ChunkProblem]:
        """Check the store before a session resumes it; steps whose chunks are damaged are
        flagged pending again, to be taken again, where the backend can take them again.

        A simulated device takes a step again identically (its noise comes from the seed and
        the step): the damaged steps' corrupt chunks are deleted (so that no step shares an
        unreadable chunk with its rewrite) and their flags cleared. A real rig or a replay cannot
        take a frame again: a damaged frame or index chunk raises
        :class:`~hwbridge.errors.DamagedDataError` naming the first bad frame. An unreadable
        progress flag only makes its step pending, on every backend (as a lost flag does).

        Returns
        -------
        list of ChunkProblem
            The damaged chunks of the steps flagged pending again, also kept in
            :attr:`recaptured`.
        """
        report = self.check()
        if report.flags_disagree or report.problems:
            self._group.attrs["complete"] = False
        flags = [problem for problem in report.problems if problem.key.startswith("progress/")]
        data = [problem for problem in report.problems if problem not in flags]
        backend = self._group.attrs.get("backend")
        if data and backend != "sim":
            damage = replace(report, problems=data).damage()
            raise DamagedDataError(
                f"{self.path}: damaged capture store: {damage}; a {backend} capture cannot "
                "take its frames again, so resuming would leave them wrong: restore the store "
                "from a copy, or capture again into a new store"
            )
        progress = array_at(self._group, "progress")
        for problem in report.problems:
            if problem.problem == "corrupt":
                (self.path / problem.key).unlink(missing_ok=True)
            for step in problem.units:
                progress[step] = False
        self._unseen = None
        self.recaptured = list(report.problems)
        return self.recaptured

    def _unit_arrays(self, camera: str) -> list[tuple[zarr.Array[Any], bool]]:
        """The per-frame arrays of ``camera`` and whether a done step must have its chunk."""
        index = group_at(self._group, f"index/{camera}")
        fields = [name for name in (*_INDEX_FIELDS, "lamp_monitor") if name in index]
        return [(self.frames(camera), True)] + [
            (array_at(index, name), name in _REQUIRED_FIELDS) for name in fields
        ]

    def _seals(self, camera: str, slots: np.ndarray | None = None) -> np.ndarray:
        """The seals of ``camera``'s frames at ``slots`` (all: ``None``); 0 where none is
        recorded, and everywhere when they cannot be read (:meth:`check` names the chunk)."""
        seal = self._array(f"index/{camera}/seal")
        try:
            values = seal[:] if slots is None else seal.get_orthogonal_selection(slots)
            return np.asarray(values, np.uint64)
        except (ValueError, RuntimeError):
            return np.zeros(seal.shape[0] if slots is None else slots.size, np.uint64)

    def _step_name(self, step: int) -> str:
        camera, slot = self._camera_and_slot(step)
        return f"camera {camera} step {step} (frame {slot})"

    def _flags(self) -> np.ndarray:
        """The progress flags; a corrupt flag chunk raises, naming it."""
        progress = self._array("progress")
        try:
            return np.asarray(progress[:], dtype=bool)
        except (ValueError, RuntimeError) as error:
            _, problems = read_flags(ChunkChecker(self.path), progress, self._step_name)
            first = problems[0] if problems else f"progress cannot be read ({error})"
            raise DamagedDataError(f"{self.path}: damaged capture store: {first}") from None

    def _array(self, key: str) -> zarr.Array[Any]:
        """The array at ``key``, opened once per store object: an open is a metadata read, and
        a capture writes and reads each step through a dozen arrays."""
        array = self._arrays.get(key)
        if array is None:
            array = self._arrays[key] = array_at(self._group, key)
        return array

    def _read(self, array: zarr.Array[Any]) -> np.ndarray:
        try:
            return np.asarray(array[:])
        except (ValueError, RuntimeError) as error:
            raise DamagedDataError(
                f"{self.path}: damaged capture store: {array.path} cannot be read "
                f"({' '.join(str(error).split())[:120]})"
            ) from None

    def _camera_and_slot(self, step: int) -> tuple[str, int]:
        if not 0 <= step < len(self._cameras):
            raise InputError(f"step: expected 0..{len(self._cameras) - 1}, got {step}")
        return self._cameras[step], self._slots[step]


def _layout(cameras: Sequence[str]) -> list[str]:
    """The nodes (groups and arrays) every capture store of ``cameras`` has."""
    nodes = ["frames", "index", "progress"]
    for camera in cameras:
        nodes += [f"frames/{camera}", f"index/{camera}"]
        nodes += [f"index/{camera}/{name}" for name in (*_INDEX_FIELDS, "lamp_monitor")]
    return nodes
