"""Capture sessions on the simulated backend: resume after SIGKILL, faults, bad input."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from hwbridge.errors import BridgeInputError
from hwbridge.plans import dark_series, estimate_duration_s, gonio_sample_run
from hwbridge.session import run_session
from hwbridge.store import CaptureStore
from twin.gonio.sim_session import demo_plan, run_demo_session

SEED = 2026


def _frames_and_index(store: CaptureStore):
    index = store.index("k4")
    index.pop("timestamp")  # wall-clock time differs between runs
    index.pop("status")
    return store.frames("k4")[:], index


def test_sigkill_at_20_random_moments_then_resume_gives_the_uninterrupted_result(tmp_path):
    reference = run_demo_session(tmp_path / "reference.capture.zarr", SEED)
    reference_frames, reference_index = _frames_and_index(reference)
    path = tmp_path / "killed.capture.zarr"
    rng = np.random.default_rng(20)
    command = [sys.executable, "-m", "twin.gonio.sim_session", str(path), str(SEED)]
    kills = 0
    while kills < 20:
        resume = ["--resume"] if path.exists() else []
        process = subprocess.Popen(
            command + resume, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        time.sleep(rng.uniform(1.5, 4.0))
        if process.poll() is None:
            os.kill(process.pid, signal.SIGKILL)
            process.wait()
            kills += 1
        elif process.returncode == 0:
            break  # finished before the kill: restart from scratch to keep killing
        else:
            pytest.fail(f"session exited with {process.returncode}")
    if not path.exists() or not CaptureStore.open(path).complete:
        subprocess.run(command + (["--resume"] if path.exists() else []), check=True)
    resumed = CaptureStore.open(path)
    assert resumed.complete and resumed.pending_steps() == []
    frames, index = _frames_and_index(resumed)
    assert frames.shape == reference_frames.shape == (len(demo_plan()), 32, 32)
    np.testing.assert_array_equal(frames, reference_frames)  # bit-identical, nothing duplicated
    for name, values in reference_index.items():
        np.testing.assert_array_equal(index[name], values)
    assert kills >= 1


def test_timeouts_and_disconnects_on_one_call_in_20_are_retried_and_recorded(tmp_path):
    store = run_demo_session(tmp_path / "faulty.capture.zarr", SEED, fault_rate=0.05)
    assert store.complete
    statuses = store.index("k4")["status"]
    assert any("timeout" in status for status in statuses)
    assert any("disconnect" in status for status in statuses)
    reference = run_demo_session(tmp_path / "clean.capture.zarr", SEED)
    np.testing.assert_array_equal(store.frames("k4")[:], reference.frames("k4")[:])


def test_plans_and_dry_run_duration():
    plan = dark_series("k4", [0.1, 1.0], 50)
    assert len(plan) == 100 and all(step["kind"] == "dark" for step in plan)
    run = gonio_sample_run("k4", [0, 1], [400.0, 410.0], [1.0, 0.5])
    assert [step["band_nm"] for step in run] == [400.0, 410.0, 400.0, 410.0]
    assert estimate_duration_s(run) == pytest.approx(3.0 + 4 * 0.13 + 2 * 6.0)
    with pytest.raises(BridgeInputError, match="exposures"):
        gonio_sample_run("k4", [0], [400.0, 410.0], [1.0])
    with pytest.raises(BridgeInputError, match="exposure_s"):
        dark_series("k4", [-1.0])


def test_bad_sessions_are_refused_and_overwrite_nothing(tmp_path):
    path = tmp_path / "done.capture.zarr"
    run_demo_session(path, SEED)
    before = CaptureStore.open(path).frames("k4")[:]
    with pytest.raises(BridgeInputError, match="exists"):
        run_demo_session(path, SEED)
    with pytest.raises(BridgeInputError, match="same plan and seed"):
        run_demo_session(path, SEED + 1, resume=True)
    np.testing.assert_array_equal(CaptureStore.open(path).frames("k4")[:], before)
    with pytest.raises(BridgeInputError, match="cameras"):
        run_session(tmp_path / "x.zarr", demo_plan(), cameras={}, rig={}, backend="sim", seed=0)


def test_dome_white_and_chart_plans():
    from hwbridge.plans import chart_photographs, dome_run, white_reference_run

    plan = dome_run(
        ["rgb0", "rgb1"],
        "k4",
        stage_positions=2,
        leds=3,
        rgb_exposure_s=0.05,
        spectral_exposure_s=0.2,
        spectral_bands_nm=[450.0, 550.0],
    )
    per_position = 3 + 3 * 3  # alignment frames of 3 cameras, then 3 LEDs x 3 cameras
    assert len(plan) == 2 * per_position
    spectral = [step for step in plan if step["camera"] == "k4" and step["kind"] == "sample"]
    assert [step["band_nm"] for step in spectral] == [450.0, 550.0, 450.0, 550.0, 450.0, 550.0]
    assert {step["view_id"] for step in plan} == {0, 1}
    white = white_reference_run("k4", [400.0, 410.0], [1.0, 0.8])
    assert [step["kind"] for step in white] == ["white", "white"]
    assert len(chart_photographs("rgb0", [0.01, 0.02], [0, 1, 2])) == 6


def test_an_exposure_outside_the_camera_range_stops_the_session_cleanly(tmp_path):
    plan = dark_series("k4", [5000.0], 1)  # the K4 allows up to 600 s
    from twin.components.lamps import HMILamp
    from twin.devices.sim_devices import SimCamera, VirtualRig
    from twin.gonio.signals import WhiteReferenceSignal
    from twin.sensor.model import Sensor

    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    camera = SimCamera(
        VirtualRig(), sensor, WhiteReferenceSignal(sensor, HMILamp()), np.zeros(1), name="k4"
    )
    with pytest.raises(ValueError, match="outside"):
        run_session(
            tmp_path / "s.zarr", plan, cameras={"k4": camera}, rig={}, backend="sim", seed=0
        )
    store = CaptureStore.open(tmp_path / "s.zarr")
    assert not store.complete and store.pending_steps() == [0]
