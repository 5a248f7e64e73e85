"""Capture and processing over a Dask cluster (ARCHITECTURE.md, "Scale").

``spectwin capture`` and ``spectwin process`` run in one process unless told otherwise: with
``--workers N`` they start a ``LocalCluster`` of ``N`` worker processes of one thread each, with
``--scheduler ADDRESS`` (or ``DASK_SCHEDULER_ADDRESS``) they use a running cluster, whose workers
must reach the stores under the same path (a shared filesystem). :func:`dask_client` opens either.

Capture (:func:`run_capture`): the coordinator creates the capture store, or reopens it to
resume, splits the pending steps into tasks of consecutive steps that share a view
(:func:`view_tasks`) and submits them. A worker builds the devices from their recipe
(:class:`twin.devices.sim_devices.SimGonioDevices`), so it renders a view once for all the frames
of a task, writes its steps' frames (one chunk per frame, so no chunk has two writers) and returns
their records; the coordinator, the one writer of the index and the progress flags, writes them
as the tasks finish (a step is flagged done after its frame and index are written). A frame's
noise is drawn from ``(seed, step)``, its exposure starts at the time the
plan gives the step (:func:`hwbridge.plans.plan_start_times_s`: lamp flicker and drift stay
modelled) and renders are deterministic whatever the thread count, so the frames and every index
field but the wall-clock ``timestamp`` are bit-identical to a serial capture's. Every worker sets
its own Mitsuba variant and gives Dr.Jit as many threads as it runs tasks (:class:`RendererSetup`),
so ``N`` one-thread workers do not oversubscribe ``N`` cores.

Processing (:func:`run_process`): the coordinator prepares the run once (dark model, white
factors, drift reference: :func:`recon.btf.processing.prepare_gonio_run`), creates the BTF store
and submits the pending direction pairs in tasks of up to :data:`MAX_TASK_PAIRS`
(:func:`pair_tasks`); a worker opens the capture store once per task, registers its pairs and
writes their chunks. Workers return metadata only (steps done, pairs registered coarsely or not
at all); the coordinator alone writes the stores' attributes (``complete``, the outcome lists).

One writer per store (:mod:`hwbridge.lock`): the coordinator holds the store's writer lock for
the whole run, serial or distributed, and the workers write their chunks inside it. When the run
ends early (an error, SIGINT or SIGTERM) the coordinator sets a Dask ``Event`` that every task
checks before each step (capture) or pair (processing) and waits for the running tasks to end
before it lets the lock go, so no worker writes to a store whose lock is free (a second Ctrl-C
stops the waiting). The workers of a ``LocalCluster`` ignore SIGINT, so that Ctrl-C in a terminal,
which reaches the whole process group, stops them through the coordinator, between steps.

Examples
--------
>>> with dask_client(workers=2) as client:  # doctest: +SKIP
...     run_gonio_measurement("run.capture.zarr", exposures_s, client=client)
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Mapping
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from distributed import Client, Event, Future, LocalCluster, WorkerPlugin, as_completed, wait

from hwbridge.lock import StoreLock
from hwbridge.schema import NO_VIEW, RigAttrs
from hwbridge.session import (
    SessionSettings,
    SignalStop,
    StopRequest,
    capture_pending,
    capture_steps,
    locked_session_store,
    raise_if_interrupted,
)
from hwbridge.store import CaptureStore, FrameRecord
from recon.btf.inputs import InputDigests
from recon.btf.processing import (
    GonioRun,
    PairOutcomes,
    open_btf_store,
    prepare_gonio_run,
    process_pairs,
    record_outcomes,
)
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.errors import InputError
from recon.progress import progress_steps
from twin.devices.sim_devices import DeviceRecipe

__all__ = [
    "RendererSetup",
    "cluster_description",
    "dask_client",
    "pair_tasks",
    "run_capture",
    "run_process",
    "view_tasks",
]

MAX_TASK_STEPS = 64
"""Most steps per capture task: a gonio pair's 33 bands stay in one task (one render), the
calibration's 750 response-series frames of one view spread over several."""

MAX_TASK_PAIRS = 16
"""Most direction pairs per processing task: a task opens the capture store once for all of
them (about a second for the index of a campaign of 100 000 frames)."""


@contextmanager
def dask_client(
    workers: int = 1, scheduler: str | None = None, *, connect_timeout_s: float = 10.0
) -> Iterator[Client | None]:
    """A Dask client for the duration of the ``with`` block, or ``None`` to run serially.

    Parameters
    ----------
    workers
        Worker processes of a ``LocalCluster`` on this machine, one thread each; 0 or 1 (and no
        ``scheduler``) run serially.
    scheduler
        Address of a running scheduler (``tcp://host:8786``); its workers are used.
    connect_timeout_s
        How long to try reaching ``scheduler``.

    Yields
    ------
    Client or None
        Connected to the cluster, which a ``LocalCluster`` outlives no longer than the block.
    """
    if workers < 0:
        raise InputError(f"workers: expected 0 or more worker processes, got {workers}")
    if scheduler and workers > 1:
        raise InputError(
            f"workers: {workers} local workers and the scheduler {scheduler!r} were both given; "
            "a scheduler's cluster brings its own workers"
        )
    if scheduler:
        try:
            client = Client(scheduler, timeout=connect_timeout_s)
        except (OSError, TimeoutError, ValueError) as error:
            raise InputError(
                f"scheduler {scheduler!r}: no Dask scheduler answered within "
                f"{connect_timeout_s:g} s ({error}); start one (dask scheduler), or unset "
                "--scheduler and DASK_SCHEDULER_ADDRESS to run without it"
            ) from None
        with client:
            yield client
        return
    if workers <= 1:
        yield None
        return
    with _workers_ignore_ctrl_c():
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # No dashboard; the scheduler's health page on a free port, so that clusters of
            # concurrent runs do not compete for port 8787.
            scheduler_kwargs={"dashboard_address": ":0"},
            silence_logs=logging.ERROR,
        )
    with cluster, Client(cluster) as client:
        yield client


@contextmanager
def _workers_ignore_ctrl_c() -> Iterator[None]:
    """Start worker processes that ignore SIGINT (an ignored signal stays ignored in a child):
    Ctrl-C in a terminal reaches every process of the foreground group, and the workers are to
    finish their current step and stop when the coordinator says so (:func:`run_capture`), not
    die in the middle of it. Ctrl-C is ignored while the cluster starts."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous if previous is not None else signal.SIG_DFL)


def cluster_description(client: Client | None) -> str:
    """``"serial"`` or the scheduler's address and its number of workers."""
    if client is None:
        return "serial"
    return f"{client.scheduler.address} ({len(client.nthreads())} workers)"


class RendererSetup(WorkerPlugin):
    """Run on every worker process as it joins: Dr.Jit gets as many threads as the worker runs
    tasks (unless ``SPECTWIN_THREADS`` says otherwise) and the Mitsuba variant is set
    (:func:`twin.render.variant.activate`, once per process)."""

    name = "spectwin-renderer"

    def setup(self, worker: Any) -> None:
        from twin.render.variant import activate

        os.environ.setdefault("SPECTWIN_THREADS", str(worker.state.nthreads))
        activate()


def view_tasks(
    plan: list[dict], steps: list[int], max_steps: int = MAX_TASK_STEPS
) -> list[list[int]]:
    """Split ``steps`` (ascending) into tasks of consecutive steps with one view each, at most
    ``max_steps`` long: a worker renders the view once per task and owns its steps' chunks.

    Examples
    --------
    >>> plan = [{"view_id": v} for v in (-1, -1, 0, 0, 0, 1)]
    >>> view_tasks(plan, [0, 1, 2, 3, 4, 5], max_steps=2)
    [[0, 1], [2, 3], [4], [5]]
    """
    if max_steps < 1:
        raise InputError(f"max_steps: expected at least 1, got {max_steps}")
    tasks: list[list[int]] = []
    for step in steps:
        view = plan[step].get("view_id", NO_VIEW)
        last = tasks[-1] if tasks else None
        if (
            last is not None
            and len(last) < max_steps
            and last[-1] == step - 1
            and plan[last[-1]].get("view_id", NO_VIEW) == view
        ):
            last.append(step)
        else:
            tasks.append([step])
    return tasks


class _EventStop(StopRequest):
    """In a worker: stop when the coordinator sets the run's Dask event."""

    def __init__(self, event: Event):
        self._event = event

    def __call__(self) -> bool:
        return bool(self._event.is_set())


@contextmanager
def _stoppable_tasks(client: Client) -> Iterator[tuple[Event, list[Future]]]:
    """A stop event for the tasks submitted into the yielded list; when the block ends (however
    it ends) the event is set and every task is waited for, so none still writes afterwards."""
    event = Event(f"spectwin-stop-{uuid.uuid4().hex}", client=client)
    futures: list[Future] = []
    try:
        yield event, futures
    finally:
        event.set()  # tasks not started return at once, running ones after their current step
        with contextlib.suppress(Exception):  # tasks that failed or were lost with a worker
            wait(futures)
        with contextlib.suppress(Exception):
            event.clear()


def _gather(
    futures: list[Future],
    description: str,
    total: int,
    show_progress: bool,
    stop: StopRequest | None = None,
    received: Callable[[Any], None] = lambda metadata: None,
) -> list:
    """The metadata of tasks that return ``(steps done, metadata)``, in the order they finish,
    each handed to ``received`` as it comes, advancing a bar of ``total`` steps, until all are
    done or ``stop`` asks to stop; a task's error is raised (a capture or process cut short
    resumes with ``resume``)."""
    stop = stop or StopRequest()
    results = []
    completed = as_completed(futures, with_results=True)
    with progress_steps(description, total, enabled=show_progress) as advance:
        while not completed.is_empty() and not stop():
            if not completed.has_ready():
                time.sleep(0.05)
                continue
            _, result = next(completed)
            received(result[1])
            advance(result[0])
            results.append(result[1])
    return results


@functools.lru_cache(maxsize=4)
def _worker_store(path: str, stamp: tuple[int, int]) -> CaptureStore:
    """The capture store at ``path``, opened once per worker process and version of its root
    metadata (``stamp``: its modification time and size): the plan of a full campaign is tens
    of MB of JSON, which a task per direction pair would otherwise read again."""
    return CaptureStore.open(path)


def _capture_task(
    store_path: str,
    devices: DeviceRecipe,
    seed: int,
    steps: list[int],
    stop: Event,
) -> tuple[int, list[tuple[int, FrameRecord]]]:
    if stop.is_set():
        return 0, []
    metadata = os.stat(Path(store_path) / "zarr.json")
    taken = capture_steps(
        _worker_store(store_path, (metadata.st_mtime_ns, metadata.st_size)),
        steps,
        devices(seed, steps),
        record=False,
        stop=_EventStop(stop),
    )
    return len(taken), taken


def run_capture(
    store: str | Path,
    plan: list[dict[str, Any]],
    devices: DeviceRecipe,
    *,
    rig: RigAttrs | Mapping[str, Any],
    seed: int,
    resume: bool = False,
    show_progress: bool = False,
    client: Client | None = None,
    max_steps: int = MAX_TASK_STEPS,
) -> CaptureStore:
    """Capture ``plan`` into ``store`` in this process, or over ``client``'s cluster.

    Parameters
    ----------
    store
        The capture store, ``<name>.capture.zarr``.
    plan
        One dict per step (:mod:`hwbridge.plans`).
    devices
        Builds the session's devices for the seed and the steps they take; it must pickle to
        run on a cluster (e.g. :class:`twin.devices.sim_devices.SimGonioDevices`).
    rig, seed
        Stored with the plan (:class:`hwbridge.session.SessionSettings`), with the recipe's
        ``backend``.
    resume
        Continue an interrupted capture (serial or distributed, either way).
    show_progress
        A progress bar over the steps.
    client
        ``None`` to capture in this process (:func:`hwbridge.session.capture_pending`), else a
        Dask client (:func:`dask_client`).
    max_steps
        Most steps per task (:func:`view_tasks`).

    Returns
    -------
    CaptureStore
        The complete store.

    Raises
    ------
    StoreBusy
        Another writer holds the store (:mod:`hwbridge.lock`).
    SessionInterrupted
        SIGINT or SIGTERM stopped the capture (on a cluster: after the workers' current steps).
    """
    settings = SessionSettings(
        rig=rig, backend=devices.backend, seed=seed, resume=resume, show_progress=show_progress
    )
    with SignalStop() as stop, ExitStack() as held:
        sizes = devices(seed, [])  # the frame shapes, read from staged devices
        held.callback(sizes.unstage)
        session = held.enter_context(locked_session_store(store, plan, sizes, settings))
        sizes.unstage()  # a real device is staged once at a time
        pending = session.pending_steps()
        if client is None:
            capturing = devices(seed, pending)
            held.callback(capturing.unstage)
            capture_pending(session, capturing, settings, stop)
            return session
        client.register_plugin(RendererSetup(), name=RendererSetup.name)
        [recipe] = client.scatter([devices], broadcast=True, hash=False)
        path = str(session.path.resolve())

        def record(taken: list[tuple[int, FrameRecord]]) -> None:
            if taken:
                steps, records = zip(*taken, strict=True)
                with stop.writing():
                    session.write_index(steps, records)
                    session.mark_done(steps, check_complete=False)

        try:
            with _stoppable_tasks(client) as (event, futures):
                futures += [
                    client.submit(_capture_task, path, recipe, seed, steps, event, pure=False)
                    for steps in view_tasks(plan, pending, max_steps)
                ]
                _gather(futures, "capture", len(pending), show_progress, stop, record)
        except KeyboardInterrupt:
            if not stop():
                raise
        raise_if_interrupted(session, stop)
        session.refresh_complete()
    return session


def _process_task(
    run: GonioRun,
    btf_path: str,
    pairs: list[int],
    manual_corners: dict[str, np.ndarray] | None,
    stop: Event,
) -> tuple[int, PairOutcomes]:
    btf = BTFStore.open(btf_path, writable=True)
    done: list[None] = []
    outcomes = process_pairs(
        run,
        btf,
        pairs,
        manual_corners=manual_corners,
        check_complete=False,
        advance=lambda: done.append(None),
        stop=_EventStop(stop),
    )
    return len(done), outcomes


def pair_tasks(pairs: list[int], workers: int) -> list[list[int]]:
    """Split the pending ``pairs`` into processing tasks of at most :data:`MAX_TASK_PAIRS`
    consecutive pairs, at least four tasks per worker where there are pairs enough (so that
    the workers finish together)."""
    count = max(-(-len(pairs) // MAX_TASK_PAIRS), min(len(pairs), 4 * workers))
    return [chunk.tolist() for chunk in np.array_split(np.asarray(pairs, int), count) if chunk.size]


def _btf_lock(out: Path, resume: bool) -> StoreLock:
    """The writer lock of the BTF store ``out``: of the store when resuming one (checked to be a
    BTF store first), else a reservation of the name, moved into the store once it exists."""
    if resume and out.exists():
        BTFStore.open(out)
        return StoreLock.acquire(out)
    return StoreLock.reserve(out)


def run_process(
    capture: str | Path | CaptureStore,
    calibration: GonioCalibration,
    out: str | Path,
    *,
    texels: int | None = None,
    manual_corners: dict[str, np.ndarray] | None = None,
    resume: bool = False,
    show_progress: bool = False,
    client: Client | None = None,
    digests: InputDigests | None = None,
) -> BTFStore:
    """Turn a measurement run into a BTF store in this process (as
    :func:`recon.btf.processing.process_gonio`) or over ``client``'s cluster, one task per
    direction pair; the parameters are ``process_gonio``'s. The BTF store's writer lock
    (:mod:`hwbridge.lock`) is held throughout.

    Returns
    -------
    BTFStore
        The store, complete unless some pairs were not registered (``unregistered_pairs``).

    Raises
    ------
    StoreBusy
        Another writer holds the BTF store.
    """
    with _btf_lock(Path(out), resume) as lock:
        store = capture if isinstance(capture, CaptureStore) else CaptureStore.open(capture)
        run = prepare_gonio_run(store, calibration)
        btf = open_btf_store(run, out, texels=texels, resume=resume, digests=digests)
        lock.move_into()
        pending = btf.pending_pairs()
        if client is None:
            with progress_steps("process", len(pending), enabled=show_progress) as advance:
                outcomes = [
                    process_pairs(
                        run,
                        btf,
                        pending,
                        manual_corners=manual_corners,
                        advance=advance,
                        store=store,
                    )
                ]
            record_outcomes(btf, outcomes)
            return btf
        [context] = client.scatter([run], broadcast=True, hash=False)
        path = str(btf.path.resolve())
        with _stoppable_tasks(client) as (event, futures):
            futures += [
                client.submit(_process_task, context, path, task, manual_corners, event, pure=False)
                for task in pair_tasks(pending, len(client.nthreads()))
            ]
            outcomes = _gather(futures, "process", len(pending), show_progress)
        record_outcomes(btf, outcomes)
        btf.refresh_complete()
    return btf
