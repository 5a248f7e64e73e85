"""Read frames out of a capture store for calibration, whatever produced it.

Simulated sessions, replays of real captures and real sessions all write the same capture store
(``hwbridge.store``); calibration code reads frames through :func:`select_frames` and never needs
to know the backend.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hwbridge.dome_layout import camera_steps
from hwbridge.schema import PlanStep
from hwbridge.store import CaptureStore
from recon.errors import InputError

__all__ = ["FrameSelection", "plan_frames", "select_frames"]


@dataclass(frozen=True)
class FrameSelection:
    """Frames ``(n, H, W)`` as float64 DN and their index fields, in capture order."""

    frames: np.ndarray
    exposure_s: np.ndarray
    band_nm: np.ndarray
    light_id: np.ndarray
    view_id: np.ndarray
    backend: str


def select_frames(
    store: str | Path | CaptureStore,
    camera: str,
    *,
    kind: str,
    band_nm: float | None = None,
    exposure_s: float | None = None,
) -> FrameSelection:
    """The frames of ``camera`` of one ``kind``, optionally one band and/or exposure time."""
    store = store if isinstance(store, CaptureStore) else CaptureStore.open(store)
    if not store.complete:
        raise InputError(
            f"{store.path}: the capture is incomplete ({len(store.pending_steps())} steps pending)"
        )
    index = store.index(camera, ("kind", "band_nm", "exposure_s", "light_id", "view_id"))
    mask = index["kind"] == kind
    if band_nm is not None:
        mask &= np.isclose(index["band_nm"], band_nm)
    if exposure_s is not None:
        mask &= np.isclose(index["exposure_s"], exposure_s)
    slots = np.flatnonzero(mask)
    if slots.size == 0:
        raise InputError(
            f"{store.path}: no {kind!r} frames of camera {camera!r} match band={band_nm}, "
            f"exposure={exposure_s}"
        )
    return FrameSelection(
        frames=store.read_frames(camera, slots).astype(np.float64),
        exposure_s=index["exposure_s"][slots],
        band_nm=index["band_nm"][slots],
        light_id=index["light_id"][slots],
        view_id=index["view_id"][slots],
        backend=store.metadata.backend,
    )


def plan_frames(
    store: CaptureStore, camera: str, **settings: object
) -> tuple[np.ndarray, list[PlanStep]]:
    """The frames ``(n, H, W)`` (float64 DN) of ``camera`` whose plan steps have ``settings``
    (fields of :class:`~hwbridge.schema.PlanStep`, e.g. ``kind="geometric"``, ``light_id=5``;
    settings the index lacks, such as a dome's ``tilt_deg``, included), in capture order, and
    those steps."""
    plan = store.metadata.plan
    steps = camera_steps(plan, camera)
    slots = [
        slot
        for slot, step in enumerate(steps)
        if all(getattr(plan[step], name) == value for name, value in settings.items())
    ]
    if not slots:
        raise InputError(f"{store.path}: no frames of camera {camera!r} with {settings}")
    frames = store.read_frames(camera, slots).astype(np.float64)
    return frames, [plan[steps[slot]] for slot in slots]
