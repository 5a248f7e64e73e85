"""Run a capture plan on any backend into a capture store, resumably.

For each pending step: move to the step's view (when it names one), switch its LED on (when an
LED array is given), tune the filter (when it names a band), set the exposure, take the frame,
record the lamp monitor; then, for a run of steps of one view at a time, write their frames,
their index, and flag them done. A session interrupted
at any moment (crash, SIGKILL, power loss) is continued with ``resume=True``: steps already
flagged are skipped, a step that was cut short is taken again into the same slot.

The devices (:class:`SessionDevices`) are typed by the protocols of :mod:`hwbridge.protocols`;
the session's settings (:class:`SessionSettings`) are one frozen object. Cameras with a
:class:`~hwbridge.protocols.Shutter` get it closed for dark frames. With ``leds`` (an LedArray)
each step's ``light_id`` is switched on alone at the array's drive current (``-2``: all LEDs, the
dome's alignment frames; a ``light_id`` the array does not have stops the session with its
one-line error). With a ``monitor`` (:class:`~hwbridge.protocols.LampMonitor`) the lamp spectrum
is recorded with every lit frame (thesis 3.3: the i1 tracks the lamp at every measurement point).
Device timeouts are retried with exponential backoff, disconnected devices are staged again, and
both are recorded in the frame's ``status``. The session tells the devices nothing but the
step's settings: simulated devices that reproduce a step's frame bit for bit, whatever session
takes it, know the steps they take from where they were built (``twin.devices.sim_devices``).

:func:`run_session` does it all in one process: it opens the store
(:func:`locked_session_store`) and captures its pending steps (:func:`capture_pending`). The
halves serve a distributed capture (``twin.devices.cluster``): :func:`open_session_store`
creates (or reopens to resume) the store once, in the coordinator, and :func:`capture_steps`
runs a subset of the steps into it, in a worker that writes those steps' frames (one chunk each)
and returns their records, which the coordinator, the one writer of the index and the flags,
records.

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
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from types import FrameType
from typing import Any, TypeVar

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
from hwbridge.protocols import (
    Camera,
    LampMonitor,
    LedArray,
    Positioner,
    Shutter,
    Stageable,
    TunableFilter,
)
from hwbridge.schema import RigAttrs
from hwbridge.store import CaptureStore, FrameRecord

__all__ = [
    "SessionDevices",
    "SessionSettings",
    "SignalStop",
    "StopRequest",
    "capture_pending",
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

    def _handle(self, signum: int, frame: FrameType | None) -> None:
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


_Result = TypeVar("_Result")
_Device = TypeVar("_Device")


def _with_retries(
    action: Callable[[], _Result], device: object, retries: int, backoff_s: float
) -> tuple[_Result, list[str]]:
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
            if isinstance(device, Stageable):
                device.stage()
    raise AssertionError("unreachable")  # pragma: no cover


@dataclass(frozen=True)
class SessionDevices:
    """The devices of a session.

    Attributes
    ----------
    cameras
        Camera id (as the plan names it) to camera.
    tunable_filter, positioner
        Needed when the plan names bands or views.
    monitor
        Records the lamp spectrum with every lit frame.
    leds
        Switches on the LEDs the steps name (their ``light_id``); without it, lights are not
        switched.
    """

    cameras: Mapping[str, Camera]
    tunable_filter: TunableFilter | None = None
    positioner: Positioner | None = None
    monitor: LampMonitor | None = None
    leds: LedArray | None = None

    def unstage(self) -> None:
        """Release every device that was staged (closing a real device's port)."""
        others = (self.tunable_filter, self.positioner, self.monitor, self.leds)
        for device in (*self.cameras.values(), *others):
            if isinstance(device, Stageable):
                device.unstage()


@dataclass(frozen=True)
class SessionSettings:
    """How a session runs, and what its store records besides the plan.

    Attributes
    ----------
    rig, backend, seed
        Stored with the plan as the store's attributes (``rig``: the rig's model, a
        :class:`~hwbridge.schema.RigAttrs`, or its JSON form) (``backend``: ``"sim"``, ``"real"`` or
        ``"replay"``).
    resume
        Continue the store instead of creating it; it must hold the same plan and seed. Steps
        flagged done whose chunks are missing or corrupt are taken again on the simulated
        backend and refused on the others (:meth:`~hwbridge.store.CaptureStore.prepare_resume`).
    retries, backoff_s
        Retries of a device call that times out or disconnects, and the first wait (doubling).
    show_progress
        A progress bar over the steps, on standard error.
    """

    rig: RigAttrs | Mapping[str, Any]
    backend: str
    seed: int
    resume: bool = False
    retries: int = 3
    backoff_s: float = 0.01
    show_progress: bool = True


def _check_devices(plan: list[dict[str, Any]], devices: SessionDevices) -> None:
    unknown = sorted({step["camera"] for step in plan} - set(devices.cameras))
    if unknown:
        raise InputError(f"plan: names cameras {unknown} that the session was not given")
    if any("band_nm" in step for step in plan) and devices.tunable_filter is None:
        raise InputError("plan: steps name filter bands but no tunable_filter was given")
    if any(step.get("view_id", -1) != -1 for step in plan) and devices.positioner is None:
        raise InputError("plan: steps name views but no positioner was given")


def _given(device: _Device | None, role: str, step: int) -> _Device:
    """``device``, which step ``step`` needs as its ``role``."""
    if device is None:
        raise InputError(f"plan: step {step} needs a {role} but none was given")
    return device


def open_session_store(
    store_path: str | Path,
    plan: list[dict[str, Any]],
    devices: SessionDevices,
    settings: SessionSettings,
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
    settings
        Its ``rig``, ``backend`` and ``seed`` are stored with the plan; with ``resume`` the
        store is reopened instead.

    Returns
    -------
    CaptureStore
        The store, with :meth:`~hwbridge.store.CaptureStore.pending_steps` still to capture.
    """
    _check_devices(plan, devices)
    path = Path(store_path)
    seed = settings.seed
    if settings.resume:
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
    monitor = devices.monitor
    return CaptureStore.create(
        path,
        rig=settings.rig,
        backend=settings.backend,
        seed=seed,
        plan=plan,
        cameras={name: camera.frame_shape for name, camera in devices.cameras.items()},
        monitor_samples=monitor.samples if monitor is not None else 0,
    )


@contextmanager
def locked_session_store(
    store_path: str | Path,
    plan: list[dict[str, Any]],
    devices: SessionDevices,
    settings: SessionSettings,
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
    if settings.resume:
        if path.exists():
            CaptureStore.open(path)  # a capture store, before its folder gets a lock file
        lock = StoreLock.acquire(path)
    else:
        lock = StoreLock.reserve(path)
    with lock:
        store = open_session_store(path, plan, devices, settings)
        lock.move_into()
        yield store


_WRITE_STEPS = 512  # most steps held before they are written
_WRITE_BYTES = 64 << 20  # most frame bytes held


class _PendingWrites:
    """Frames and records taken but not yet written, written together: the frames of a run of
    consecutive steps in one call (their chunks concurrently), the index and the flags after
    them, in the order that keeps every step flagged done complete."""

    def __init__(self, store: CaptureStore, *, record: bool, check_complete: bool) -> None:
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
        Plan steps to take, in this order (steps done already are taken again).
    devices
        The session's devices.
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
    stop = stop or StopRequest()
    pending = _PendingWrites(store, record=record, check_complete=check_complete)
    taken: list[tuple[int, FrameRecord]] = []
    try:
        for step in steps:
            if stop():
                break
            planned = plan[step]
            view = int(planned.get("view_id", -1))
            light = int(planned.get("light_id", -1))
            if pending.due(view):
                with stop.writing():
                    pending.flush()
            camera = devices.cameras[planned["camera"]]
            faults: list[str] = []
            if view != -1:
                positioner = _given(devices.positioner, "positioner", step)
                _, seen = _with_retries(
                    partial(positioner.set, {"view_id": view}), positioner, retries, backoff_s
                )
                faults += seen
            leds = devices.leds
            if leds is not None and light != -1:
                switch = (
                    partial(leds.set, np.ones(leds.count, bool))
                    if light == ALL_LEDS
                    else partial(leds.light, light)
                )
                _, seen = _with_retries(switch, leds, retries, backoff_s)
                faults += seen
            if "band_nm" in planned:
                tunable_filter = _given(devices.tunable_filter, "tunable_filter", step)
                _, seen = _with_retries(
                    partial(tunable_filter.set, planned["band_nm"]),
                    tunable_filter,
                    retries,
                    backoff_s,
                )
                faults += seen
            camera.set_exposure(planned["exposure_s"])
            if isinstance(camera, Shutter):
                camera.set_shutter(planned["kind"] != "dark")
            (frame, metadata), seen = _with_retries(camera.snap, camera, retries, backoff_s)
            faults += seen
            spectrum = None
            monitor = devices.monitor
            if monitor is not None and planned["kind"] != "dark":
                _, seen = _with_retries(monitor.trigger, monitor, retries, backoff_s)
                faults += seen
                (reading,) = monitor.read().values()
                spectrum = reading["value"]
            frame_record = FrameRecord(
                kind=planned["kind"],
                exposure_s=planned["exposure_s"],
                timestamp=float(metadata.get("timestamp", time.time())),
                light_id=light,
                view_id=view,
                band_nm=float(planned.get("band_nm", float("nan"))),
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
    plan: list[dict[str, Any]],
    devices: SessionDevices,
    settings: SessionSettings,
) -> CaptureStore:
    """Capture every pending step of ``plan``; returns the (complete) store.

    The store's writer lock is held throughout (:func:`locked_session_store`), and SIGINT or
    SIGTERM stop the session between frames (:class:`SignalStop`).

    Parameters
    ----------
    store_path
        The store, ``<name>.capture.zarr``; never overwritten.
    plan
        One dict per step (:mod:`hwbridge.plans`).
    devices
        The session's devices.
    settings
        The store's attributes, resuming, retries and the progress bar.

    Returns
    -------
    CaptureStore
        The complete store.

    Raises
    ------
    StoreBusy
        Another writer holds the store.
    SessionInterrupted
        A signal stopped the session before its last step; ``resume=True`` continues it.
    """
    with (
        SignalStop() as stop,
        locked_session_store(store_path, plan, devices, settings) as store,
    ):
        capture_pending(store, devices, settings, stop)
    return store


def capture_pending(
    store: CaptureStore, devices: SessionDevices, settings: SessionSettings, stop: StopRequest
) -> None:
    """Capture the pending steps of an open session store (:func:`locked_session_store`) in
    this process, with ``settings``' retries and progress bar, until ``stop`` asks to stop.

    Raises
    ------
    SessionInterrupted
        ``stop`` asked to stop before the last step.
    """
    columns = (
        TextColumn("capture"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeRemainingColumn(),
    )
    total = len(store.attrs["plan"])
    pending = store.pending_steps()
    with Progress(
        *columns, console=Console(stderr=True), disable=not settings.show_progress
    ) as progress:
        task = progress.add_task("capture", total=total, completed=total - len(pending))
        try:
            capture_steps(
                store,
                pending,
                devices,
                retries=settings.retries,
                backoff_s=settings.backoff_s,
                advance=lambda: progress.advance(task),
                stop=stop,
            )
        except KeyboardInterrupt:
            if not stop():
                raise  # not a signal of this session's
    if not store.complete:  # a writer killed after its last flag, before marking complete
        store.refresh_complete()
    raise_if_interrupted(store, stop)


def raise_if_interrupted(store: CaptureStore, stop: StopRequest) -> None:
    """Raise :class:`~hwbridge.errors.SessionInterrupted` when ``stop`` asked to stop before
    every step of ``store`` was done."""
    if stop():
        pending = len(store.pending_steps())
        if pending:
            total = len(store.attrs["plan"])
            raise SessionInterrupted(store.path, total - pending, total)
