"""Capture and processing over a two-worker Dask LocalCluster (twin.devices.cluster) give the
results of one process, bit for bit (timestamps are wall-clock time and differ, and each store
seals its frames with its own identity); a design sweep runs its points on the cluster's
workers."""

import dataclasses
import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from hwbridge.errors import InputError, SessionInterrupted, StoreBusy
from hwbridge.lock import StoreLock, lock_owner
from hwbridge.plans import plan_start_times_s
from hwbridge.session import SessionSettings, capture_steps, open_session_store
from hwbridge.store import CaptureStore
from recon.btf.processing import process_gonio
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
from twin.cli.app import app
from twin.components.lamps import HMILamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.devices import cluster as cluster_module
from twin.devices.cluster import dask_client, pair_tasks, view_tasks
from twin.devices.sim_devices import SimGonioDevices
from twin.gonio.capture import CAMERA_ID, GonioPairs, run_gonio_measurement
from twin.gonio.signals import WhiteReferenceSignal
from twin.gonio.sim_session import demo_plan, demo_program, run_demo_session
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor

runner = CliRunner()
BANDS_NM = np.asarray(LiquidCrystalTunableFilter.varispec("VS-10").band_centres_nm, np.float64)
EXPOSURES_S = np.full(BANDS_NM.size, 6 * HMI_FLICKER_PERIOD_S)
# The dome sweep's renders at 4 samples per pixel (the capture's 16 by default; fewer render 4
# as well, twin.render.spectra.rendered_spp), of one RGB camera: errors 11.4 and 7.8 % (10.4 and
# 7.5 % at 16 spp; 22.9 and 21.7 % with two RGB cameras, which take half as much CPU time again).
SPP_DOME = 4
RGB_CAMERAS_DOME = 1


@pytest.fixture(scope="module")
def client():
    with dask_client(workers=2) as client:
        yield client


@pytest.fixture(scope="module")
def captures(client, tmp_path_factory):
    """A two-pair run at 96 px captured serially and on the cluster."""
    root = tmp_path_factory.mktemp("distributed")
    pairs = GonioPairs(
        load_rig("gonio"),
        direction(np.array([30.0, 30.0]), np.array([0.0, 0.0])),
        direction(np.array([0.0, 30.0]), np.array([0.0, 135.0])),
    )
    stores = {
        name: run_gonio_measurement(
            root / f"{name}.capture.zarr",
            EXPOSURES_S,
            pairs=pairs,
            pixels=96,
            spp=16,
            seed=3,
            client=cluster,
        )
        for name, cluster in (("serial", None), ("cluster", client))
    }
    return root, stores


def _without_timestamps(store: CaptureStore, camera: str):
    index = store.index(camera)
    del index["timestamp"], index["seal"]  # the seals are keyed by each store's own identity
    return store.frames(camera)[:], index


def _assert_same_capture(store: CaptureStore, reference: CaptureStore, camera: str) -> None:
    frames, index = _without_timestamps(store, camera)
    reference_frames, reference_index = _without_timestamps(reference, camera)
    np.testing.assert_array_equal(frames, reference_frames)
    assert index.keys() == reference_index.keys()
    for name, values in reference_index.items():
        np.testing.assert_array_equal(index[name], values, err_msg=name)
    assert store.complete and reference.complete
    assert store.attrs["plan"] == reference.attrs["plan"]


@pytest.mark.render
def test_a_capture_on_two_workers_is_bit_identical_to_the_serial_one(captures):
    _, stores = captures
    serial, cluster = stores["serial"], stores["cluster"]
    assert serial.frames(CAMERA_ID).shape == (8 + 33 + 2 * 33, 96, 96)  # darks, white, pairs
    _assert_same_capture(cluster, serial, CAMERA_ID)
    # The frames are not trivially equal: lit, noisy, and the lamp monitor saw the drift.
    _, index = _without_timestamps(cluster, CAMERA_ID)
    assert np.unique(cluster.frames(CAMERA_ID)[90]).size > 50
    assert np.ptp(index["lamp_monitor"][index["kind"] == "sample"].sum(axis=1)) > 0


@pytest.mark.render
def test_process_on_two_workers_from_the_command_line_equals_the_serial_btf(client, captures):
    """``spectwin process --scheduler`` on the module's running cluster (whose workers have
    imported the renderer and processing already; ``--workers N`` opens a ``LocalCluster``
    through the same :func:`dask_client` as the module's cluster)."""
    root, stores = captures
    calibration = GonioCalibration.identity(EXPOSURES_S, BANDS_NM, HMI_FLICKER_PERIOD_S)
    calibration.save(root / "cal.json")
    serial = process_gonio(stores["serial"], calibration, root / "serial.btf.zarr", texels=32)
    result = runner.invoke(
        app,
        [
            "process",
            str(stores["serial"].path),
            "--calibration",
            str(root / "cal.json"),
            "--out",
            str(root / "cluster.btf.zarr"),
            "--texels",
            "32",
            "--scheduler",
            client.scheduler.address,
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["complete"] and summary["cluster"] == f"{client.scheduler.address} (2 workers)"
    cluster = BTFStore.open(root / "cluster.btf.zarr")
    np.testing.assert_array_equal(cluster.reflectance(), serial.reflectance())
    np.testing.assert_array_equal(cluster.corners_xy(), serial.corners_xy())
    for name in ("complete", "coarse_corner_pairs", "unregistered_pairs", "calibration"):
        assert cluster.attrs[name] == serial.attrs[name]
    assert serial.complete and np.isfinite(serial.reflectance()).all()


@pytest.mark.render
def test_a_dome_sweep_of_t_base_on_the_cluster_doubles_the_spectral_exposure(client, tmp_path):
    """Two dome designs that differ only in the weakest band's exposure, run as Dask tasks on the
    module's two workers (``spectwin sweep --scheduler``; ``--workers N`` opens a LocalCluster
    through the same :func:`dask_client`): t_lambda = t_base / sqrt(E L) (thesis 10.4) doubles
    every band exposure with t_base, the RGB sets stay."""
    sweep = tmp_path / "dome.yaml"
    sweep.write_text(
        yaml.safe_dump(
            {
                "name": "tiny dome t_base sweep",
                "rig": "dome",
                "plan": {
                    "stage_positions": 1,
                    "leds": 4,
                    "rgb_cameras": RGB_CAMERAS_DOME,
                    "texels": 32,
                    "spp": SPP_DOME,
                    "dark_frames": 4,
                    "schedule_images": 4,
                },
                "parameters": {"plan.longest_band_s": [2.0, 4.0]},
            },
            sort_keys=False,
        )
    )
    out = tmp_path / "out"
    address = client.scheduler.address
    result = runner.invoke(
        app, ["sweep", str(sweep), "--out", str(out), "--scheduler", address, "--json"]
    )
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["workers"] == 2
    short, long = (row["measures"] for row in json.loads((out / "table.json").read_text()))
    assert long["spectral_exposure_h"] / short["spectral_exposure_h"] == pytest.approx(2, rel=1e-6)
    assert long["rgb_exposure_h"] == short["rgb_exposure_h"]
    assert long["capture_time_h"] > short["capture_time_h"]
    for measures in (short, long):
        assert measures["pairs"] == 4 * RGB_CAMERAS_DOME and 0 < measures["error_pct"] < 30


@pytest.mark.parametrize(
    ("pairs", "workers", "sizes"),
    [
        (3192, 2, {15, 16}),  # 200 tasks: a full glossy campaign opens its store 200 times
        (60, 2, {7, 8}),  # four tasks per worker at least
        (3, 2, {1}),
    ],
)
def test_processing_tasks_take_consecutive_pairs_in_small_batches(pairs, workers, sizes):
    pending = list(range(5, 5 + pairs))
    tasks = pair_tasks(pending, workers)
    assert [pair for task in tasks for pair in task] == pending
    assert {len(task) for task in tasks} == sizes
    assert len(tasks) >= min(pairs, 4 * workers)


def _demo_devices(seed: int) -> SimGonioDevices:
    """The devices of :func:`twin.gonio.sim_session.run_demo_session` (white standard, 32 px)."""
    sensor = Sensor("coolsnap_k4", roi=(32, 32))
    signal = WhiteReferenceSignal(sensor, HMILamp())
    plan = demo_plan()
    return SimGonioDevices("k4", sensor, signal, plan_start_times_s(plan), 2, fault_seed=seed)


def test_a_capture_cut_short_resumes_on_the_cluster_with_the_same_frames(client, tmp_path):
    reference = run_demo_session(tmp_path / "reference.capture.zarr", 11)
    path, plan, devices = tmp_path / "resumed.capture.zarr", demo_plan(), _demo_devices(11)
    store = open_session_store(path, plan, devices(11), SessionSettings({}, "sim", 11))
    steps = range(len(plan) // 2)
    capture_steps(store, steps, devices(11, steps))  # then the session died
    assert not store.complete
    resumed = run_demo_session(path, 11, resume=True, client=client)
    _assert_same_capture(resumed, reference, "k4")


GATE_TIMEOUT_S = 300
"""How long a gated camera waits for its gate (and the test for written frames): the gate opens
after the coordinator's first gather, which takes a minute or more on a loaded 2-core machine; a
gate that never opens still fails the test."""


def _done(path) -> int:
    try:
        store = CaptureStore.open(path)
    except InputError:  # not created yet
        return 0
    return len(store.attrs["plan"]) - len(store.pending_steps())


class _GatedCamera:
    """A camera taking ``steps`` that holds every step from ``first_gated`` on until the file
    ``gate`` exists."""

    def __init__(self, camera, steps, gate: Path, first_gated: int):
        self._camera, self._steps, self._taken = camera, list(steps), 0
        self._gate, self._first_gated = gate, first_gated

    def __getattr__(self, name):
        return getattr(self._camera, name)

    def snap(self):
        deadline = time.monotonic() + GATE_TIMEOUT_S
        while self._steps[self._taken] >= self._first_gated and not self._gate.exists():
            assert time.monotonic() < deadline, "the gate was never opened"
            time.sleep(0.01)
        frame = self._camera.snap()
        self._taken += 1
        return frame


class _GatedDevices:
    """The demo's device recipe with its camera behind a :class:`_GatedCamera` (pickled by value
    for the workers)."""

    backend = "sim"

    def __init__(self, devices, gate: Path, first_gated: int):
        self._devices, self._gate, self._first_gated = devices, gate, first_gated

    def __call__(self, seed, steps):
        session = self._devices(seed, steps)
        cameras = {
            name: _GatedCamera(camera, steps, self._gate, self._first_gated)
            for name, camera in session.cameras.items()
        }
        return dataclasses.replace(session, cameras=cameras)


def test_sigint_stops_a_capture_on_the_cluster_inside_the_coordinators_lock(
    client, tmp_path, monkeypatch
):
    """The coordinator holds the store's lock while the workers write; on SIGINT the workers
    stop after their current step, the coordinator returns only when none writes any more, and
    a resume on the cluster ends with the uninterrupted frames. Steps from 20 on wait for a gate
    that opens only once the coordinator has stopped gathering, so the SIGINT always finds work
    left, whatever the machine's speed."""
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    path, gate, first_gated = tmp_path / "stopped.capture.zarr", tmp_path / "gate", 20
    program = demo_program(11)
    seen: dict[str, object] = {}
    gather = cluster_module._gather

    def gather_then_open_the_gate(*args, **kwargs):
        try:
            return gather(*args, **kwargs)
        finally:
            gate.touch()

    monkeypatch.setattr(cluster_module, "_gather", gather_then_open_the_gate)

    def interrupt_once_frames_are_written() -> None:
        deadline = time.monotonic() + GATE_TIMEOUT_S
        while _done(path) < 5 and time.monotonic() < deadline:
            time.sleep(0.02)
        seen["owner"] = lock_owner(path)
        try:
            StoreLock.acquire(path).release()
        except StoreBusy as busy:
            seen["busy"] = str(busy)
        os.kill(os.getpid(), signal.SIGINT)

    interrupter = threading.Thread(target=interrupt_once_frames_are_written)
    interrupter.start()
    try:
        with pytest.raises(SessionInterrupted) as stopped:
            cluster_module.run_capture(
                path,
                program.plan,
                _GatedDevices(program.devices, gate, first_gated),
                rig=program.rig,
                seed=program.seed,
                client=client,
                max_steps=1,
            )
    finally:
        gate.touch()
        interrupter.join()
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert seen["owner"].pid == os.getpid()  # the coordinator's lock, not a worker's
    assert f"is being written by PID {os.getpid()}" in seen["busy"]
    done = _done(path)
    assert stopped.value.done == done and 5 <= done <= first_gated < len(demo_plan())
    time.sleep(1.0)
    assert _done(path) == done  # no worker wrote after the coordinator returned
    assert not (path / ".writer.lock").exists()
    reference = run_demo_session(tmp_path / "reference.capture.zarr", 11)
    resumed = run_demo_session(path, 11, resume=True, client=client)
    _assert_same_capture(resumed, reference, "k4")


def test_a_capture_on_the_cluster_is_refused_while_another_writer_holds_the_store(client, tmp_path):
    path, plan, devices = tmp_path / "held.capture.zarr", demo_plan(), _demo_devices(11)
    store = open_session_store(path, plan, devices(11), SessionSettings({}, "sim", 11))
    capture_steps(store, range(4), devices(11, range(4)))
    with StoreLock.acquire(path):
        with pytest.raises(StoreBusy, match=f"PID {os.getpid()}"):
            run_demo_session(path, 11, resume=True, client=client)
    assert store.pending_steps() == list(range(4, len(plan)))


def test_workers_of_one_session_fill_disjoint_steps_of_one_store(tmp_path):
    plan, devices = demo_plan(), _demo_devices(1)
    path = tmp_path / "shared.capture.zarr"
    coordinator = open_session_store(path, plan, devices(1), SessionSettings({}, "sim", 1))
    tasks = view_tasks(plan, coordinator.pending_steps())
    assert [len(task) for task in tasks] == [6, 33, 33]
    for task in tasks[::-1]:  # each "worker" opens the store, builds its own devices, writes
        # its frames and returns their records; the coordinator writes index and flags
        taken = capture_steps(CaptureStore.open(path), task, devices(1, task), record=False)
        assert [step for step, _ in taken] == task
        assert set(task) <= set(coordinator.pending_steps())  # frames written, not yet recorded
        steps, records = zip(*taken, strict=True)
        coordinator.write_index(steps, records)
        coordinator.mark_done(steps, check_complete=False)
    assert not coordinator.complete and coordinator.pending_steps() == []
    assert coordinator.refresh_complete() and coordinator.complete
    assert list(coordinator.index("k4")["kind"]) == [step["kind"] for step in plan]


def test_view_tasks_split_runs_of_one_view_and_respect_gaps_and_the_size_limit():
    plan = [{"view_id": view} for view in (-1, -1, 0, 0, 0, 0, 1, 1)]
    assert view_tasks(plan, list(range(8)), max_steps=3) == [[0, 1], [2, 3, 4], [5], [6, 7]]
    assert view_tasks(plan, [0, 2, 3, 5, 7]) == [[0], [2, 3], [5], [7]]
    with pytest.raises(InputError, match="max_steps"):
        view_tasks(plan, [0], max_steps=0)


def test_cluster_errors_name_the_scheduler_and_the_conflict(tmp_path):
    address = "tcp://127.0.0.1:9"  # the discard port: nothing listens there
    with pytest.raises(InputError, match="tcp://127.0.0.1:9.*no Dask scheduler"):
        with dask_client(scheduler=address, connect_timeout_s=0.5):
            pass
    store = tmp_path / "x.capture.zarr"
    both = runner.invoke(
        app, ["capture", "demo", str(store), "--workers", "2", "--scheduler", address]
    )
    assert both.exit_code == 2 and "scheduler" in both.output
    negative = runner.invoke(app, ["capture", "demo", str(store), "--workers", "-1"])
    assert negative.exit_code == 2
    assert not store.exists()
