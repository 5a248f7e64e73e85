"""Run a capture plan on any backend into a capture store, resumably.

For each pending step: move to the step's view (when it names one), switch its LED on (when an
LED array is given), tune the filter (when it names a band), set the exposure, take the frame,
record the lamp monitor; then, for a run of steps of one view at a time, write their frames,
their index, and flag them done. A session interrupted
at any moment (crash, SIGKILL, power loss) is continued with ``resume=True``: steps already
flagged are skipped, a step that was cut short is taken again into the same slot.

Devices that simulate noise can implement ``set_step(seed, step)`` to derive it from the step
index, so that a resumed session reproduces the frames of an uninterrupted one bit for bit;
cameras with ``set_shutter(open)`` get it closed for dark frames. With ``leds`` (an LedArray of
``led_count`` LEDs) each step's ``light_id`` is switched on alone at the array's drive current
(``-2``: all LEDs, the dome's alignment frames; a ``light_id`` the array does not have stops the
session with its one-line error). With a ``monitor`` (Spectrometer) the lamp spectrum is recorded
with every lit frame (thesis 3.3: the i1 tracks the lamp at every measurement point). Device
timeouts are retried with exponential backoff, disconnected devices are staged again, and both are
recorded in the frame's ``status``.

:func:`run_session` does it all in one process. Its two halves serve a distributed capture
(``twin.devices.cluster``): :func:`open_session_store` creates (or reopens to resume) the store
once, in the coordinator, and :func:`capture_steps` runs a subset of the steps into it, in a
worker that writes those steps' frames (one chunk each) and returns their records, which the
coordinator, the one writer of the index and the flags, records.

One writer per store: :func:`locked_session_store` holds the store's writer lock
(:mod:`hwbridge.lock`) from before the store is created (or reopened) until the session ends; a
second session on the same store is refused with :class:`~hwbridge.errors.StoreBusy`. The
workers of a distributed capture write inside their coordinator's lock.

Stopping: :class:`SignalStop` turns SIGINT (Ctrl-C) and SIGTERM into a request to stop after the
frame being taken; a second signal abandons that frame (never one being written). A frame is
flagged done only after its frame and index are written, so the store holds exactly the steps
flagged done, and :func:`run_session` raises :class:`~hwbridge.errors.SessionInterrupted`
naming how many. ``resume=True`` continues it.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Required, TypedDict

import numpy as np
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from hwbridge.dome_layout import ALL_LEDS
from hwbridge.errors import (
    DeviceDisconnected,
    DeviceTimeout,
    InputError,
    SessionInterrupted,
)
from hwbridge.lock import StoreLock
from hwbridge.store import CaptureStore, FrameRecord

__all__ = [
    "SessionDevices",
    "SignalStop",
    "StopRequest",
    "capture_steps",
    "locked_session_store",
    "open_session_store",
    "raise_if_interrupted",
    "run_session",
]


class StopRequest:
    """Whether a capture should stop before its next frame: never, unless a subclass says so
    (:class:`SignalStop`; a Dask event in :mod:`twin.devices.cluster`)."""

    def __call__(self) -> bool:
        return False

    @contextmanager
    def writing(self) -> Iterator[None]:
        """Around the writing of a frame, its index and its progress flag."""
        yield


class SignalStop(StopRequest):
    """SIGINT (Ctrl-C) and SIGTERM as requests to stop, for the duration of a ``with`` block.

    The first signal asks the capture to stop after the frame it is taking (true from then
    on); a second one abandons that frame at once (``KeyboardInterrupt``), unless the frame is
    being written, which always finishes. Outside the main thread, where Python cannot handle
    signals, it never asks to stop; a signal the process ignores stays ignored.
    """

    _SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.received: list[int] = []
        self._writing = False
        self._previous: dict[int, Any] = {}

    def __call__(self) -> bool:
        return bool(self.received)

    def _handle(self, signum: int, frame: object) -> None:
        self.received.append(signum)
        if len(self.received) > 1 and not self._writing:
            raise KeyboardInterrupt

    @contextmanager
    def writing(self) -> Iterator[None]:
        self._writing = True
        try:
            yield
        finally:
            self._writing = False

    def __enter__(self) -> SignalStop:
        if threading.current_thread() is threading.main_thread():
            for number in self._SIGNALS:
                previous = signal.getsignal(number)
                if previous is not signal.SIG_IGN:
                    self._previous[number] = previous
                    signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for number, previous in self._previous.items():
            signal.signal(number, previous if previous is not None else signal.SIG_DFL)
        self._previous.clear()


def _with_retries(action, device: Any, retries: int, backoff_s: float) -> tuple[Any, list[str]]:
    """Call ``action``; on a timeout wait and retry, on a disconnect stage ``device`` again and
    retry, with exponential backoff. Returns the result and the names of the faults seen."""
    faults: list[str] = []
    for attempt in range(retries + 1):
        try:
            return action(), faults
        except (DeviceTimeout, DeviceDisconnected) as fault:
            faults.append("disconnect" if isinstance(fault, DeviceDisconnected) else "timeout")
            if attempt == retries:
                raise
            time.sleep(backoff_s * 2**attempt)
            if hasattr(device, "stage"):
                device.stage()
    raise AssertionError("unreachable")  # pragma: no cover


class SessionDevices(TypedDict, total=False):
    """The devices of a session, named as :func:`run_session`'s keywords.

    ``cameras`` maps camera ids to cameras; ``tunable_filter``, ``positioner``, ``monitor``
    (a Spectrometer) and ``leds`` (an LedArray of ``led_count`` LEDs) are needed when the plan
    names bands, views, lit frames to record or lights.
    """

    cameras: Required[dict[str, Any]]
    tunable_filter: Any
    positioner: Any
    monitor: Any
    leds: Any
    led_count: int


def _check_devices(plan: list[dict], devices: SessionDevices) -> None:
    unknown = sorted({step["camera"] for step in plan} - set(devices["cameras"]))
    if unknown:
        raise InputError(f"plan: names cameras {unknown} that the session was not given")
    if any("band_nm" in step for step in plan) and devices.get("tunable_filter") is None:
        raise InputError("plan: steps name filter bands but no tunable_filter was given")
    if any(step.get("view_id", -1) != -1 for step in plan) and devices.get("positioner") is None:
        raise InputError("plan: steps name views but no positioner was given")


def open_session_store(
    store_path: str | Path,
    plan: list[dict],
    devices: SessionDevices,
    *,
    rig: dict[str, Any],
    backend: str,
    seed: int,
    resume: bool = False,
) -> CaptureStore:
    """Create the capture store of a session, or reopen it to resume.

    Parameters
    ----------
    store_path
        The store, ``<name>.capture.zarr``; never overwritten.
    plan
        One dict per step (:mod:`hwbridge.plans`).
    devices
        The session's devices; their frame shapes and monitor samples size the store.
    rig, backend, seed
        Stored with the plan as the store's attributes.
    resume
        Reopen an existing store instead; it must hold the same plan and seed. Steps flagged
        done whose chunks are missing or corrupt are taken again on the simulated backend and
        refused on the others (:meth:`~hwbridge.store.CaptureStore.prepare_resume`).

    Returns
    -------
    CaptureStore
        The store, with :meth:`~hwbridge.store.CaptureStore.pending_steps` still to capture.
    """
    _check_devices(plan, devices)
    path = Path(store_path)
    if resume:
        store = CaptureStore.open(path)
        stored = store.attrs
        if stored["plan"] != plan or stored["seed"] != seed:
            differ = "seed" if stored["plan"] == plan else "plan"
            raise InputError(
                f"{path}: resume needs the same plan and seed as the stored session (the "
                f"{differ} differs; the store's seed is {stored['seed']}, its plan "
                f"{len(stored['plan'])} steps; this session's seed {seed}, plan {len(plan)} steps)"
            )
        store.prepare_resume()  # damaged steps: taken again (simulated) or refused (real)
        return store
    monitor = devices.get("monitor")
    return CaptureStore.create(
        path,
        rig=rig,
        backend=backend,
        seed=seed,
        plan=plan,
        cameras={name: camera.frame_shape for name, camera in devices["cameras"].items()},
        monitor_samples=monitor.samples if monitor is not None else 0,
    )


@contextmanager
def locked_session_store(
    store_path: str | Path,
    plan: list[dict],
    devices: SessionDevices,
    *,
    rig: dict[str, Any],
    backend: str,
    seed: int,
    resume: bool = False,
) -> Iterator[CaptureStore]:
    """:func:`open_session_store` under the store's writer lock, held until the block ends.

    A new store's name is reserved before it is created and the lock moves into it once it
    exists (:class:`hwbridge.lock.StoreLock`); a store to resume is checked to be a capture store
    before its folder gets a lock file.

    Raises
    ------
    StoreBusy
        Another writer holds the store (or is creating it).
    """
    path = Path(store_path)
    if resume:
        if path.exists():
            CaptureStore.open(path)  # a capture store, before its folder gets a lock file
        lock = StoreLock.acquire(path)
    else:
        lock = StoreLock.reserve(path)
    with lock:
        store = open_session_store(
            path, plan, devices, rig=rig, backend=backend, seed=seed, resume=resume
        )
        lock.move_into()
        yield store


_WRITE_STEPS = 512  # most steps held before they are written
_WRITE_BYTES = 64 << 20  # most frame bytes held


class _PendingWrites:
    """Frames and records taken but not yet written, written together: the frames of a run of
    consecutive steps in one call (their chunks concurrently), the index and the flags after
    them, in the order that keeps every step flagged done complete."""

    def __init__(self, store: CaptureStore, *, record: bool, check_complete: bool):
        self._store, self._record, self._check_complete = store, record, check_complete
        self._steps: list[int] = []
        self._frames: list[np.ndarray] = []
        self._records: list[FrameRecord] = []
        self._bytes = 0
        self._view: int | None = None
        # A real frame cannot be taken again: it is written as soon as it is taken.
        self._most_steps = _WRITE_STEPS if store.attrs.get("backend") == "sim" else 1

    def add(self, step: int, frame: np.ndarray, record: FrameRecord) -> None:
        self._steps.append(step)
        self._frames.append(frame)
        self._records.append(record)
        self._bytes += frame.nbytes
        self._view = record.view_id

    def due(self, next_view: int) -> bool:
        """Whether to write before the next step: it moves to another view (a gonio pair, a
        dome stage position), or enough waits (a real capture's frame never waits). A dome
        position's LEDs are written several at a time: each camera's frames of consecutive
        LEDs lie in consecutive slots, so a write is a few long runs, not one per LED."""
        return bool(self._steps) and (
            next_view != self._view
            or len(self._steps) >= self._most_steps
            or self._bytes >= _WRITE_BYTES
        )

    def flush(self) -> None:
        if not self._steps:
            return
        self._store.write_frames(self._steps, self._frames)
        if self._record:
            self._store.write_index(self._steps, self._records)
            self._store.mark_done(self._steps, check_complete=self._check_complete)
        self._steps, self._frames, self._records, self._bytes = [], [], [], 0


def capture_steps(
    store: CaptureStore,
    steps: Iterable[int],
    devices: SessionDevices,
    *,
    seed: int,
    retries: int = 3,
    backoff_s: float = 0.01,
    check_complete: bool = True,
    record: bool = True,
    advance: Callable[[], None] = lambda: None,
    stop: StopRequest | None = None,
) -> list[tuple[int, FrameRecord]]:
    """Capture ``steps`` of the store's plan into their slots and flag each one done.

    The frames of consecutive steps of one view are written together (at most 512 steps or
    64 MiB of a simulated capture; a real one writes every frame when it is taken), then
    their index, then their flags; a step is flagged done only once its frame and
    index are written, also when the capture stops or fails on the way.

    Parameters
    ----------
    store
        A store made by :func:`open_session_store`.
    steps
        Plan steps to take, in this order (steps done already are taken again, identically
        when the devices derive their noise from the step).
    devices
        The session's devices.
    seed
        The session seed (``set_step(seed, step)`` of cameras that have it).
    retries, backoff_s
        Retries of a device call that times out or disconnects, and the first wait (doubling).
    check_complete
        Mark the store complete after its last step.
    record
        Write the index and the flags. ``False`` (a worker of a distributed capture) writes the
        frames only: its coordinator, the index's one writer, records the returned steps
        (:meth:`~hwbridge.store.CaptureStore.write_index`,
        :meth:`~hwbridge.store.CaptureStore.mark_done`).
    advance
        Called after each step (a progress bar).
    stop
        Asked before each step whether to stop there (:class:`SignalStop`); its ``writing()``
        surrounds the writing of frames, index and flags.

    Returns
    -------
    list of (int, FrameRecord)
        The steps taken and their records (fewer than ``steps`` when ``stop`` said so).
    """
    plan = store.attrs["plan"]
    cameras = devices["cameras"]
    tunable_filter = devices.get("tunable_filter")
    positioner = devices.get("positioner")
    monitor = devices.get("monitor")
    leds = devices.get("leds")
    led_count = devices.get("led_count", 0)
    stop = stop or StopRequest()
    pending = _PendingWrites(store, record=record, check_complete=check_complete)
    taken: list[tuple[int, FrameRecord]] = []
    try:
        for step in steps:
            if stop():
                break
            settings = plan[step]
            if pending.due(int(settings.get("view_id", -1))):
                with stop.writing():
                    pending.flush()
            camera = cameras[settings["camera"]]
            faults: list[str] = []
            if settings.get("view_id", -1) != -1:
                _, seen = _with_retries(
                    lambda s=settings: positioner.set({"view_id": s["view_id"]}),
                    positioner,
                    retries,
                    backoff_s,
                )
                faults += seen
            if leds is not None and settings.get("light_id", -1) != -1:
                light = int(settings["light_id"])
                switch = (
                    (lambda: leds.set(np.ones(led_count, bool)))
                    if light == ALL_LEDS
                    else (lambda led=light: leds.light(led))
                )
                _, seen = _with_retries(switch, leds, retries, backoff_s)
                faults += seen
            if "band_nm" in settings:
                _, seen = _with_retries(
                    lambda s=settings: tunable_filter.set(s["band_nm"]),
                    tunable_filter,
                    retries,
                    backoff_s,
                )
                faults += seen
            camera.set_exposure(settings["exposure_s"])
            if hasattr(camera, "set_shutter"):
                camera.set_shutter(settings["kind"] != "dark")
            if hasattr(camera, "set_step"):
                camera.set_step(seed, step)
            (frame, metadata), seen = _with_retries(camera.snap, camera, retries, backoff_s)
            faults += seen
            spectrum = None
            if monitor is not None and settings["kind"] != "dark":
                _, seen = _with_retries(monitor.trigger, monitor, retries, backoff_s)
                faults += seen
                (reading,) = monitor.read().values()
                spectrum = reading["value"]
            frame_record = FrameRecord(
                kind=settings["kind"],
                exposure_s=settings["exposure_s"],
                timestamp=float(metadata.get("timestamp", time.time())),
                light_id=int(settings.get("light_id", -1)),
                view_id=int(settings.get("view_id", -1)),
                band_nm=float(settings.get("band_nm", float("nan"))),
                lamp_monitor=spectrum,
                status="ok" if not faults else "ok after " + ", ".join(faults),
            )
            pending.add(step, np.asarray(frame), frame_record)
            taken.append((step, frame_record))
            advance()
    finally:
        with stop.writing():
            pending.flush()
    return taken


def run_session(
    store_path: str | Path,
    plan: list[dict],
    *,
    cameras: dict[str, Any],
    tunable_filter: Any | None = None,
    positioner: Any | None = None,
    monitor: Any | None = None,
    leds: Any | None = None,
    led_count: int = 0,
    rig: dict[str, Any],
    backend: str,
    seed: int,
    resume: bool = False,
    retries: int = 3,
    backoff_s: float = 0.01,
    show_progress: bool = True,
) -> CaptureStore:
    """Capture every pending step of ``plan``; returns the (complete) store.

    The store's writer lock is held throughout (:func:`locked_session_store`), and SIGINT or
    SIGTERM stop the session between frames (:class:`SignalStop`).

    Raises
    ------
    StoreBusy
        Another writer holds the store.
    SessionInterrupted
        A signal stopped the session before its last step; ``resume=True`` continues it.
    """
    devices = SessionDevices(
        cameras=cameras,
        tunable_filter=tunable_filter,
        positioner=positioner,
        monitor=monitor,
        leds=leds,
        led_count=led_count,
    )
    columns = (
        TextColumn("capture"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeRemainingColumn(),
    )
    with (
        SignalStop() as stop,
        locked_session_store(
            store_path, plan, devices, rig=rig, backend=backend, seed=seed, resume=resume
        ) as store,
    ):
        pending = store.pending_steps()
        with Progress(
            *columns, console=Console(stderr=True), disable=not show_progress
        ) as progress:
            task = progress.add_task("capture", total=len(plan), completed=len(plan) - len(pending))
            try:
                capture_steps(
                    store,
                    pending,
                    devices,
                    seed=seed,
                    retries=retries,
                    backoff_s=backoff_s,
                    advance=lambda: progress.advance(task),
                    stop=stop,
                )
            except KeyboardInterrupt:
                if not stop():
                    raise  # not a signal of this session's
        if not store.complete:  # a writer killed after its last flag, before marking complete
            store.refresh_complete()
        raise_if_interrupted(store, stop)
    return store


def raise_if_interrupted(store: CaptureStore, stop: StopRequest) -> None:
    """Raise :class:`~hwbridge.errors.SessionInterrupted` when ``stop`` asked to stop before
    every step of ``store`` was done."""
    if stop():
        pending = len(store.pending_steps())
        if pending:
            total = len(store.attrs["plan"])
            raise SessionInterrupted(store.path, total - pending, total)
