"""Run a capture plan on any backend into a capture store, resumably.

For each pending step: move to the step's view (when it names one), switch its LED on (when an
LED array is given), tune the filter (when it names a band), set the exposure, take the frame,
record the lamp monitor, write frame and index, then flag the step done. A session interrupted
at any moment (crash, SIGKILL, power loss) is continued with ``resume=True``: steps already
flagged are skipped, a step that was cut short is taken again into the same slot.

Devices that simulate noise can implement ``set_step(seed, step)`` to derive it from the step
index, so that a resumed session reproduces the frames of an uninterrupted one bit for bit;
cameras with ``set_shutter(open)`` get it closed for dark frames. With ``leds`` (an LedArray of
``led_count`` LEDs) each step's ``light_id`` is switched on alone (``-2``: all LEDs, the dome's
alignment frames). With a ``monitor`` (Spectrometer) the lamp spectrum is recorded with every lit
frame (thesis 3.3: the i1 tracks the lamp at every measurement point). Device timeouts are
retried with exponential backoff, disconnected devices are staged again, and both are recorded
in the frame's ``status``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from hwbridge.errors import BridgeInputError, DeviceDisconnected, DeviceTimeout
from hwbridge.store import CaptureStore, FrameRecord

__all__ = ["run_session"]


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
    """Capture every pending step of ``plan``; returns the (complete) store."""
    unknown = sorted({step["camera"] for step in plan} - set(cameras))
    if unknown:
        raise BridgeInputError(f"plan: names cameras {unknown} that the session was not given")
    if any("band_nm" in step for step in plan) and tunable_filter is None:
        raise BridgeInputError("plan: steps name filter bands but no tunable_filter was given")
    if any(step.get("view_id", -1) != -1 for step in plan) and positioner is None:
        raise BridgeInputError("plan: steps name views but no positioner was given")
    path = Path(store_path)
    if resume:
        store = CaptureStore.open(path)
        if store.attrs["plan"] != plan or store.attrs["seed"] != seed:
            raise BridgeInputError(
                f"{path}: resume needs the same plan and seed as the stored session"
            )
    else:
        shapes = {name: camera.frame_shape for name, camera in cameras.items()}
        store = CaptureStore.create(
            path,
            rig=rig,
            backend=backend,
            seed=seed,
            plan=plan,
            cameras=shapes,
            monitor_samples=monitor.samples if monitor is not None else 0,
        )
    pending = store.pending_steps()
    columns = (
        TextColumn("capture"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, disable=not show_progress) as progress:
        task = progress.add_task("capture", total=len(plan), completed=len(plan) - len(pending))
        for step in pending:
            settings = plan[step]
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
                pattern = np.ones(led_count, bool) if light == -2 else np.arange(led_count) == light
                _, seen = _with_retries(lambda p=pattern: leds.set(p), leds, retries, backoff_s)
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
            record = FrameRecord(
                kind=settings["kind"],
                exposure_s=settings["exposure_s"],
                timestamp=float(metadata.get("timestamp", time.time())),
                light_id=int(settings.get("light_id", -1)),
                view_id=int(settings.get("view_id", -1)),
                band_nm=float(settings.get("band_nm", float("nan"))),
                lamp_monitor=spectrum,
                status="ok" if not faults else "ok after " + ", ".join(faults),
            )
            store.write_frame(step, frame, record)
            store.mark_done(step)
            progress.advance(task)
    return store
