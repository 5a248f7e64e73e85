"""A capture store written out as the files a rig's own software writes: one TIFF per frame, a
JSON sidecar per frame and one session file.

Layout of the folder (what :mod:`hwbridge.replay` reads back with the shipped mappings
``spectwin-gonio`` and ``spectwin-dome``):

- ``frames/<camera>/<name>.tif``: the raw uint16 frame as stored, uncompressed; ``<name>`` is
  :func:`frame_name`: the plan step, the frame kind, the exposure time and, where the step sets
  them, the band, the view (a direction pair, or the dome's stage position) and the light, e.g.
  ``s000042_white_e0.2s_b550.0nm_v3.tif``;
- ``frames/<camera>/<name>.json``: the frame's sidecar (:class:`FrameSidecar`): its step, its
  camera and every field of its :class:`~hwbridge.store.FrameRecord` (timestamp, status, pose,
  the lamp monitor's spectrum), NaN written as ``null``;
- ``session.json`` (:data:`SESSION_FILE`, :class:`SessionFile`): what the rig's software knows
  of the session: the store's ``rig`` attribute, its seed, backend and software version, the
  plan (one :class:`~hwbridge.schema.PlanStep` per frame) and every camera's frame size.
  It is written last, by a rename: a folder without it is an export that did not finish.

Numbers are written so that they read back exactly: exposure times and bands in the names as
Python writes a float (``repr``), the sidecars' values in JSON at full precision.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import tifffile
from pydantic import Field

from hwbridge.dome_layout import camera_steps
from hwbridge.errors import InputError
from hwbridge.schema import Backend, FrameKind, PlanStep, StoreModel
from hwbridge.store import CaptureStore, FrameRecord

__all__ = [
    "FRAMES_FORMAT",
    "SESSION_FILE",
    "Export",
    "ExportSummary",
    "FrameSidecar",
    "SessionFile",
    "export_frames",
    "frame_name",
    "prepare_export",
]

SESSION_FILE = "session.json"
"""The session file at the root of an exported folder."""

FRAMES_FORMAT = "spectwin-frames"
"""The ``format`` of :data:`SESSION_FILE`."""


class SessionFile(StoreModel):
    """What the rig's software knows of a session: ``session.json`` of an exported folder."""

    format: Literal["spectwin-frames"] = Field(description="`spectwin-frames`")
    format_version: Literal[1] = Field(description="version of this layout")
    software_version: str = Field(description="version of the software that captured")
    backend: Backend = Field(description="`sim`, `real` or `replay`: how the frames were taken")
    seed: int = Field(ge=0, description="session seed")
    rig: dict[str, Any] = Field(description="the store's `rig` attribute (a `RigAttrs`)")
    plan: tuple[PlanStep, ...] = Field(min_length=1, description="one `PlanStep` per frame")
    cameras: dict[str, tuple[int, int]] = Field(description="every camera's frame: rows, columns")


class FrameSidecar(StoreModel):
    """The sidecar of one frame: its step and camera and its :class:`FrameRecord`'s fields."""

    step: int = Field(ge=0, description="the plan step")
    camera: str = Field(description="the camera that took it")
    kind: FrameKind = Field(description="frame kind")
    exposure_s: float = Field(ge=0, description="exposure time")
    timestamp: float = Field(description="wall-clock time of the frame")
    light_id: int = Field(description="light switched on")
    view_id: int = Field(description="view")
    band_nm: float | None = Field(description="band of the tunable filter; null: none")
    status: str = Field(description="`ok`, or the device faults retried")
    pose: tuple[float | None, ...] = Field(
        min_length=6, max_length=6, description="pose, 6 numbers; null: not recorded"
    )
    lamp_monitor: tuple[float, ...] | None = Field(
        description="the lamp monitor's spectrum; null: none"
    )

    def record(self) -> FrameRecord:
        """The frame's :class:`FrameRecord`."""
        return FrameRecord(
            kind=self.kind,
            exposure_s=self.exposure_s,
            timestamp=self.timestamp,
            light_id=self.light_id,
            view_id=self.view_id,
            band_nm=math.nan if self.band_nm is None else self.band_nm,
            status=self.status,
            pose=tuple(math.nan if value is None else value for value in self.pose),
            lamp_monitor=(
                None if self.lamp_monitor is None else np.array(self.lamp_monitor, np.float32)
            ),
        )


@dataclass(frozen=True)
class ExportSummary:
    """What :func:`export_frames` wrote: ``frames`` per camera into ``folder``."""

    folder: Path
    frames: dict[str, int]
    rig: str
    program: str


def frame_name(step: int, settings: PlanStep) -> str:
    """The file name (without suffix) of the frame of plan step ``step``.

    Examples
    --------
    >>> frame_name(42, PlanStep(camera="k4", kind="white", exposure_s=0.2, band_nm=550, view_id=3))
    's000042_white_e0.2s_b550.0nm_v3'
    >>> frame_name(7, PlanStep(camera="rgb00", kind="dark", exposure_s=0.05))
    's000007_dark_e0.05s'
    """
    parts = [f"s{step:06d}", settings.kind, f"e{settings.exposure_s!r}s"]
    if settings.band_nm is not None:
        parts.append(f"b{settings.band_nm!r}nm")
    given = settings.model_fields_set
    parts += [f"v{settings.view_id}"] if "view_id" in given else []
    parts += [f"l{settings.light_id}"] if "light_id" in given else []
    return "_".join(parts)


def _number(value: float) -> float | None:
    return None if math.isnan(value) else value


@dataclass(frozen=True)
class Export:
    """A complete capture store checked for export into a new folder (:func:`prepare_export`);
    :meth:`write` writes it."""

    store: CaptureStore
    folder: Path

    @property
    def frames(self) -> dict[str, int]:
        """Frames per camera, in the order the plan first names the cameras."""
        plan = self.store.metadata.plan
        cameras = dict.fromkeys(step.camera for step in plan)
        return {camera: len(camera_steps(plan, camera)) for camera in cameras}

    def write(self, advance: Callable[[int], object] | None = None) -> ExportSummary:
        """Write every frame and its sidecar, then ``session.json`` (module docstring).

        Parameters
        ----------
        advance
            Called with 1 after each frame written (a progress bar's step).

        Returns
        -------
        ExportSummary
            The folder and the frames written per camera.
        """
        metadata = self.store.metadata
        for camera in self.frames:
            place = self.folder / "frames" / camera
            place.mkdir(parents=True)
            index = self.store.index(camera)
            monitor = index.get("lamp_monitor")
            for slot, step in enumerate(camera_steps(metadata.plan, camera)):
                frame = self.store.read_frames(camera, [slot])[0]
                name = frame_name(step, metadata.plan[step])
                tifffile.imwrite(place / f"{name}.tif", frame)
                sidecar = FrameSidecar(
                    step=step,
                    camera=camera,
                    kind=str(index["kind"][slot]),
                    exposure_s=float(index["exposure_s"][slot]),
                    timestamp=float(index["timestamp"][slot]),
                    light_id=int(index["light_id"][slot]),
                    view_id=int(index["view_id"][slot]),
                    band_nm=_number(float(index["band_nm"][slot])),
                    status=str(index["status"][slot]),
                    pose=tuple(_number(float(value)) for value in index["pose"][slot]),
                    lamp_monitor=(
                        None
                        if monitor is None or np.isnan(monitor[slot]).all()
                        else tuple(float(value) for value in monitor[slot])
                    ),
                )
                (place / f"{name}.json").write_text(sidecar.model_dump_json(indent=1))
                if advance is not None:
                    advance(1)
        session = SessionFile(
            format=FRAMES_FORMAT,
            format_version=1,
            software_version=metadata.software_version,
            backend=metadata.backend,
            seed=metadata.seed,
            rig=metadata.rig,
            plan=metadata.plan,
            cameras={camera: self.store.frames(camera).shape[1:] for camera in self.frames},
        )
        partial = self.folder / f".{SESSION_FILE}.partial"
        partial.write_text(session.model_dump_json(indent=1, exclude_unset=True))
        os.replace(partial, self.folder / SESSION_FILE)
        rig = metadata.rig
        return ExportSummary(self.folder, self.frames, str(rig.get("rig")), str(rig.get("program")))


def prepare_export(store: CaptureStore, folder: str | Path) -> Export:
    """Check that ``store`` is complete and ``folder`` new or empty; nothing is written.

    Parameters
    ----------
    store
        The capture store to export.
    folder
        Where to write its frames.

    Returns
    -------
    Export
        :meth:`Export.write` writes the folder.

    Raises
    ------
    InputError
        If the store is incomplete or ``folder`` is a file or a folder that is not empty.
    """
    folder = Path(folder)
    pending = store.pending_steps()
    if pending:
        total = len(store.metadata.plan)
        raise InputError(
            f"{store.path}: the capture is incomplete ({len(pending)} of {total} steps pending, "
            f"first step {pending[0]}); expected a complete capture store"
        )
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise InputError(f"{folder} exists and is not an empty folder: expected a new folder")
    return Export(store, folder)


def export_frames(
    store: CaptureStore, folder: str | Path, *, advance: Callable[[int], object] | None = None
) -> ExportSummary:
    """Write every frame of a complete capture store into ``folder`` (module docstring):
    :func:`prepare_export`, then :meth:`Export.write`."""
    return prepare_export(store, folder).write(advance)
