"""Capture sessions on the simulated backend: resume after SIGKILL and SIGINT, one writer per
store, faults, bad input."""

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hwbridge.errors import InputError, SessionInterrupted, StoreBusy
from hwbridge.lock import StoreLock, lock_owner
from hwbridge.plans import dark_series, estimate_duration_s, gonio_sample_run
from hwbridge.session import SessionDevices, SessionSettings, run_session
from hwbridge.store import CaptureStore
from twin.gonio.sim_session import demo_plan, demo_program, run_demo_session

SEED = 2026


def _frames_and_index(store: CaptureStore):
    index = store.index("k4")
    index.pop("timestamp")  # wall-clock time differs between runs
    index.pop("seal")  # keyed by each store's own identity
    index.pop("status")
    return store.frames("k4")[:], index


def _check_done_steps(path: Path, reference_frames: np.ndarray) -> int:
    """Every step flagged done holds the uninterrupted run's frame; returns how many are done."""
    store = CaptureStore.open(path)
    done = sorted(set(range(len(store.attrs["plan"]))) - set(store.pending_steps()))
    frames = store.frames("k4")
    for step in done:  # the demo plan has one camera: its slot is the step
        np.testing.assert_array_equal(frames[step], reference_frames[step])
    return len(done)


def _check_complete(path: Path, reference_frames: np.ndarray, reference_index: dict) -> None:
    store = CaptureStore.open(path)
    assert store.complete and store.pending_steps() == []
    frames, index = _frames_and_index(store)
    assert frames.shape == reference_frames.shape == (len(demo_plan()), 32, 32)
    np.testing.assert_array_equal(frames, reference_frames)  # bit-identical, nothing duplicated
    for name, values in reference_index.items():
        np.testing.assert_array_equal(index[name], values)
    assert not (path / ".writer.lock").exists()


def _capture_args(path: Path) -> list[str]:
    """The demo capture of ``path`` at the seed, or its resume once the store exists (which
    continues with the store's seed)."""
    if path.exists():
        return ["capture", "resume", str(path), "--json"]
    return ["capture", "demo", str(path), "--json", "--seed", str(SEED)]


def test_20_sigkills_and_5_sigints_at_random_moments_resume_to_the_uninterrupted_frames(
    tmp_path, capture_kit
):
    """Captures of the demo program, each stopped at a seeded random moment by SIGKILL (20) or
    SIGINT (5) and continued with ``spectwin capture resume`` until complete (then begun
    afresh); in every capture, at a random moment, a second writer is started (with the first
    held by SIGSTOP, so that it cannot finish meanwhile) and must be refused, naming the first.
    Every store that completes holds the uninterrupted run's frames; after every stop, every
    step flagged done holds its frame; a SIGINT ends with exit 130 and the line saying how far
    it got."""
    reference = run_demo_session(tmp_path / "reference.capture.zarr", SEED)
    reference_frames, reference_index = _frames_and_index(reference)
    path = tmp_path / "killed.capture.zarr"
    rng = np.random.default_rng(2026)
    signals = [signal.SIGKILL] * 20 + [signal.SIGINT] * 5
    rng.shuffle(signals)
    delivered = {signal.SIGKILL: 0, signal.SIGINT: 0}
    captures = capture_kit.processes
    refused = completed = progressed = 0
    started = time.monotonic()

    def start_and_await_the_lock(args: list[str]) -> tuple[int, Path]:
        pid, stderr = captures.start(args)
        deadline = time.monotonic() + 60
        while not capture_kit.lock_names(path, pid) and capture_kit.running(pid):
            assert time.monotonic() < deadline, stderr.read_text()
            time.sleep(0.005)
        return pid, stderr

    try:
        # The moments span an uninterrupted capture's life (from its lock to its end) and a
        # quarter more, timed here on this machine as loaded as it is: a fixed 1.5 s let about
        # 70 of 95 captures finish first on a quiet machine (30 of 55 under load 7), each
        # sleeping out its moment, 95-110 s in all; now 10-17 of 35-42 (57-80 s under load 6).
        pid, stderr = start_and_await_the_lock(_capture_args(path))
        lifetime_s = time.monotonic()
        assert captures.wait(pid) == 0, stderr.read_text()
        lifetime_s = time.monotonic() - lifetime_s
        _check_complete(path, reference_frames, reference_index)
        shutil.rmtree(path)
        while signals:
            before = _check_done_steps(path, reference_frames) if path.exists() else 0
            pid, stderr = start_and_await_the_lock(_capture_args(path))
            moment = rng.uniform(0.0, 1.25 * lifetime_s)
            second_at = rng.uniform(0.0, moment)
            time.sleep(second_at)
            os.kill(pid, signal.SIGSTOP)
            held = capture_kit.lock_names(path, pid)
            if held and (owner := lock_owner(path)) and owner.pid == pid:
                second_args = ["capture", "resume" if path.exists() else "demo", str(path)]
                second, second_stderr = captures.start(second_args)
                assert captures.wait(second) == 1, second_stderr.read_text()
                lines = second_stderr.read_text().splitlines()
                assert len(lines) == 1 and lines[0].startswith("error: "), lines
                assert f"by PID {pid} on host " in lines[0] and " since " in lines[0]
                refused += 1
            os.kill(pid, signal.SIGCONT)
            time.sleep(moment - second_at)
            number = signals[0]
            os.kill(pid, number)
            code = captures.wait(pid)
            if code == 0:  # it finished before the signal: check it and begin afresh
                _check_complete(path, reference_frames, reference_index)
                shutil.rmtree(path)
                completed += 1
                assert completed < 400, "the captures finish before their signals"  # 10-17 do
                continue
            signals.pop(0)
            delivered[number] += 1
            done = _check_done_steps(path, reference_frames) if path.exists() else 0
            progressed += done > before
            total = len(demo_plan())
            if number == signal.SIGKILL:
                assert code == -signal.SIGKILL, stderr.read_text()
            else:
                assert code == 130, stderr.read_text()
                then = (
                    "the capture is complete"
                    if done == total
                    else f"continue with: spectwin capture resume {path}"
                )
                assert stderr.read_text().splitlines() == [
                    f"interrupted after {done} of {total} frames; {then}"
                ]
            if done == total:  # stopped after its last frame: finish, check, begin afresh
                # A SIGKILL after marking the store complete but before releasing the lock
                # leaves the lock file (not held; hwbridge.lock): the resume takes it over.
                stale = number == signal.SIGKILL and (path / ".writer.lock").exists()
                if stale or not CaptureStore.open(path).complete:  # or killed before the mark
                    pid, stderr = captures.start(["capture", "resume", str(path), "--json"])
                    assert captures.wait(pid) == 0, stderr.read_text()
                _check_complete(path, reference_frames, reference_index)
                shutil.rmtree(path)
                completed += 1
        pid, stderr = captures.start(_capture_args(path))
        assert captures.wait(pid) == 0, stderr.read_text()
    finally:
        captures.close()
    _check_complete(path, reference_frames, reference_index)
    assert delivered == {signal.SIGKILL: 20, signal.SIGINT: 5}
    assert refused >= 20  # all but the moments when the first had already ended
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert leftovers == []  # no reservation or half-made store of a killed creation remains
    print(
        f"{sum(delivered.values())} signals ({progressed} after the process had written frames), "
        f"{refused} second writers refused, {completed} captures completed, "
        f"{time.monotonic() - started:.1f} s"
    )


class _SignalsAtFrame:
    """The demo's white-standard signal, sending ``signals`` to this very process while it
    computes lit frame ``frame`` (the darks, shutter closed, ask for no signal)."""

    def __init__(self, inner, frame: int, signals: list[int]):
        self._inner, self._frame, self._signals, self._calls = inner, frame, signals, 0

    def __call__(self, rig, start_s: float, exposure_s: float) -> np.ndarray:
        self._calls += 1
        if self._calls == self._frame:
            for number in self._signals:
                os.kill(os.getpid(), number)
        return self._inner(rig, start_s, exposure_s)


def _demo_signalled(frame: int, signals: list[int]):
    program = demo_program(SEED)
    devices = dataclasses.replace(
        program.devices, signal=_SignalsAtFrame(program.devices.signal, frame, signals)
    )
    return dataclasses.replace(program, devices=devices)


@pytest.mark.parametrize(
    ("signals", "done"),
    [
        ([signal.SIGINT], 6 + 10),  # the frame being taken is finished and written, then stop
        ([signal.SIGTERM], 6 + 10),
        ([signal.SIGINT, signal.SIGINT], 6 + 9),  # a second Ctrl-C abandons that frame
    ],
    ids=["sigint", "sigterm", "sigint-twice"],
)
def test_a_signal_stops_the_session_between_frames_and_resume_completes_it(tmp_path, signals, done):
    path = tmp_path / "stopped.capture.zarr"
    previous = signal.getsignal(signal.SIGINT)
    with pytest.raises(SessionInterrupted) as stopped:
        _demo_signalled(10, signals).run(path)
    assert signal.getsignal(signal.SIGINT) is previous  # the session's handlers are gone
    total = len(demo_plan())
    assert (stopped.value.done, stopped.value.total) == (done, total)
    store = CaptureStore.open(path)
    assert store.pending_steps() == list(range(done, total)) and not store.complete
    assert not (path / ".writer.lock").exists()
    reference = run_demo_session(tmp_path / "reference.capture.zarr", SEED)
    reference_frames, reference_index = _frames_and_index(reference)
    assert _check_done_steps(path, reference_frames) == done
    run_demo_session(path, SEED, resume=True)
    _check_complete(path, reference_frames, reference_index)


def test_a_second_session_on_a_store_being_written_is_refused_and_writes_nothing(tmp_path):
    path = tmp_path / "busy.capture.zarr"
    with pytest.raises(SessionInterrupted):
        _demo_signalled(3, [signal.SIGINT]).run(path)
    before = CaptureStore.open(path).pending_steps()
    with StoreLock.acquire(path):  # another writer
        with pytest.raises(StoreBusy, match=rf"is being written by PID {os.getpid()} on host"):
            run_demo_session(path, SEED, resume=True)
        with pytest.raises(StoreBusy, match="is being written by PID"):
            run_demo_session(path, SEED)
    assert CaptureStore.open(path).pending_steps() == before
    with StoreLock.reserve(tmp_path / "new.capture.zarr"):  # another writer creating it
        with pytest.raises(StoreBusy, match="is being created by PID"):
            run_demo_session(tmp_path / "new.capture.zarr", SEED)
    assert not (tmp_path / "new.capture.zarr").exists()


def test_the_stale_lock_of_a_killed_session_is_taken_over(tmp_path, capture_kit):
    path = tmp_path / "stale.capture.zarr"
    command = [sys.executable, "-m", "twin.gonio.sim_session", str(path), str(SEED)]
    process = subprocess.Popen(command, cwd=capture_kit.root, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    lock_names = capture_kit.lock_names
    while not (path / "progress").exists() or not lock_names(path, process.pid, inside=True):
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.01)
    process.kill()
    process.wait()
    assert json.loads((path / ".writer.lock").read_text())["pid"] == process.pid  # left behind
    store = run_demo_session(path, SEED, resume=True)
    assert store.complete and not (path / ".writer.lock").exists()


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
    with pytest.raises(InputError, match="exposures"):
        gonio_sample_run("k4", [0], [400.0, 410.0], [1.0])
    with pytest.raises(InputError, match="exposure_s"):
        dark_series("k4", [-1.0])


def test_bad_sessions_are_refused_and_overwrite_nothing(tmp_path):
    path = tmp_path / "done.capture.zarr"
    run_demo_session(path, SEED)
    before = CaptureStore.open(path).frames("k4")[:]
    with pytest.raises(InputError, match="exists"):
        run_demo_session(path, SEED)
    with pytest.raises(InputError, match="same plan and seed"):
        run_demo_session(path, SEED + 1, resume=True)
    np.testing.assert_array_equal(CaptureStore.open(path).frames("k4")[:], before)
    with pytest.raises(InputError, match="cameras"):
        run_session(
            tmp_path / "x.zarr",
            demo_plan(),
            SessionDevices(cameras={}),
            SessionSettings({}, "sim", 0),
        )


def test_white_and_chart_plans():
    from hwbridge.plans import chart_photographs, white_reference_run

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
            tmp_path / "s.zarr",
            plan,
            SessionDevices(cameras={"k4": camera}),
            SessionSettings({}, "sim", 0),
        )
    store = CaptureStore.open(tmp_path / "s.zarr")
    assert not store.complete and store.pending_steps() == [0]
