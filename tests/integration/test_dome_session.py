"""Rendered dome captures killed and resumed, and device faults survived (the gonioreflectometer's
counterparts are in ``test_session.py``).

The capture here is smaller than the reduced capture of the benchmark (two stage positions, two
LEDs, one RGB camera and the spectral camera, 8 texels, 4 samples per pixel: 26 frames from 12
renders), so that six kills and their resumes take about half a minute; the code path is the
same at any size.
"""

from __future__ import annotations

import os
import shutil
import signal
import time

import numpy as np
import pytest

from hwbridge.store import CaptureStore
from twin.dome.programs import DomeCaptureSize, dome_run_program

pytestmark = pytest.mark.render

SEED = 2027
MATERIAL = "lego"
SIZE = DomeCaptureSize(stage_positions=2, leds=2, rgb_cameras=1, texels=8, spp=4)
KILLS = 6  # three at random moments, three once a stage position is written
ARGS = [
    "--material",
    MATERIAL,
    "--stage-positions",
    str(SIZE.stage_positions),
    "--leds",
    str(SIZE.leds),
    "--rgb-cameras",
    str(SIZE.rgb_cameras),
    "--texels",
    str(SIZE.texels),
    "--spp",
    str(SIZE.spp),
]


def _contents(store: CaptureStore) -> dict[str, dict[str, np.ndarray]]:
    """Every camera's frames and index, but the wall-clock timestamps and the seals (keyed by
    each store's own identity)."""
    cameras = dict.fromkeys(step["camera"] for step in store.attrs["plan"])
    contents = {}
    for camera in cameras:
        index = store.index(camera)
        index.pop("timestamp")
        index.pop("seal")
        contents[camera] = {"frames": store.frames(camera)[:], **index}
    return contents


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict[str, dict[str, np.ndarray]]:
    path = tmp_path_factory.mktemp("reference") / "reference.capture.zarr"
    return _contents(dome_run_program(MATERIAL, size=SIZE, seed=SEED).run(path))


def _assert_same(contents: dict, reference: dict) -> None:
    assert contents.keys() == reference.keys()
    for camera, fields in reference.items():
        for name, values in fields.items():
            np.testing.assert_array_equal(contents[camera][name], values, err_msg=name)


def _done_steps(path) -> int:
    """Steps flagged done in the store at ``path`` (0 while it does not exist)."""
    if not (path / "progress").exists():
        return 0
    store = CaptureStore.open(path)
    return len(store.attrs["plan"]) - len(store.pending_steps())


def _check_done_steps(path, reference) -> tuple[int, int]:
    """Every step flagged done holds the uninterrupted run's frame; returns (done, total)."""
    store = CaptureStore.open(path)
    plan = store.attrs["plan"]
    done = sorted(set(range(len(plan))) - set(store.pending_steps()))
    slots: dict[str, int] = {}
    for step, settings in enumerate(plan):
        camera = settings["camera"]
        slot = slots[camera] = slots.get(camera, -1) + 1
        if step in done:
            frame = store.read_frames(camera, [slot])[0]
            np.testing.assert_array_equal(frame, reference[camera]["frames"][slot])
    return len(done), len(plan)


def _capture_args(path) -> list[str]:
    """The reduced dome run of ``path`` at the seed, or its resume once the store exists (which
    continues with the store's program and settings)."""
    if path.exists():
        return ["capture", "resume", str(path), "--json"]
    return ["capture", "dome-run", str(path), "--json", *ARGS, "--seed", str(SEED)]


def test_6_sigkills_at_random_moments_resume_to_the_uninterrupted_store(
    tmp_path, capture_kit, reference
):
    """``spectwin capture dome-run`` killed by SIGKILL six times, at seeded random moments or
    once it has written the frames of a stage position (a capture writes them together, a stage
    position at a time), and continued with ``spectwin capture resume`` until complete
    (then begun afresh): after every kill every step flagged done holds the uninterrupted run's
    frame, and the completed store holds its frames and index (timestamps apart)."""
    captures = capture_kit.processes
    path = tmp_path / "killed.capture.zarr"
    rng = np.random.default_rng(SEED)
    kills = completed = progressed = 0
    started = time.monotonic()
    while kills < KILLS:
        pid, stderr = captures.start(_capture_args(path))
        deadline = time.monotonic() + 120
        while not capture_kit.lock_names(path, pid) and capture_kit.running(pid):
            assert time.monotonic() < deadline, stderr.read_text()
            time.sleep(0.005)
        if kills % 2:  # every other kill once it has written a stage position's frames
            written = _done_steps(path)
            while capture_kit.running(pid) and _done_steps(path) == written:
                assert time.monotonic() < deadline, stderr.read_text()
                time.sleep(0.01)
        else:
            time.sleep(rng.uniform(0.0, 4.0))
        os.kill(pid, signal.SIGKILL)
        code = captures.wait(pid)
        if code == 0:  # it finished before the signal: check it and begin afresh
            _assert_same(_contents(CaptureStore.open(path)), reference)
            shutil.rmtree(path)
            completed += 1
            continue
        assert code == -signal.SIGKILL, stderr.read_text()
        kills += 1
        if path.exists():
            done, total = _check_done_steps(path, reference)
            progressed += 0 < done < total
    pid, stderr = captures.start(_capture_args(path))
    assert captures.wait(pid) == 0, stderr.read_text()
    store = CaptureStore.open(path)
    assert store.complete
    _assert_same(_contents(store), reference)
    assert progressed >= 2  # kills in a partly written store (half of them wait for one)
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert leftovers == []
    print(
        f"{kills} kills ({progressed} in a partly written store), {completed} captures "
        f"completed, {time.monotonic() - started:.1f} s"
    )


def test_device_faults_on_one_call_in_20_are_survived_and_recorded(tmp_path, reference):
    """Timeouts and disconnects injected into one device call in 20 (rotation stage, LEDs,
    filter, cameras) are retried: the capture completes with the uninterrupted run's frames, and
    the frames whose calls failed say so in their status."""
    program = dome_run_program(MATERIAL, size=SIZE, seed=SEED, fault_rate=0.05)
    store = program.run(tmp_path / "faulty.capture.zarr")
    assert store.complete
    contents = _contents(store)
    statuses = [status for camera in contents.values() for status in camera["status"]]
    assert any("timeout" in status for status in statuses)
    assert any("disconnect" in status for status in statuses)
    assert all(status == "ok" or status.startswith("ok after ") for status in statuses)
    for camera, fields in reference.items():
        np.testing.assert_array_equal(contents[camera]["frames"], fields["frames"])
