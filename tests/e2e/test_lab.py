"""The dome captured through an emulated lab (``spectwin lab emulate`` + ``capture --devices``):
the real drivers of the stage, the LEDs and the LCTF talk to their emulators on pseudo-terminals,
the twin's cameras render what the devices read back, and the BTF is the simulated capture's.
A SIGKILL of the capture and a lab that goes away mid-capture both resume to the same BTF;
``spectwin lab check`` names a device that does not answer.

Reduced dome: 2 LEDs, 1 RGB camera, 16 texels at 4 spp (the frames are compared bit for bit,
not with a truth: 32 texels at 16 spp rendered 54 of the calibration's 70 s under load 7, these
10), 2 darks per exposure, 1 stage position.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

from hwbridge.store import CaptureStore
from twin.cli.app import app

pytestmark = pytest.mark.render
pytest.importorskip("thorlabs_apt_protocol")  # the stage driver's extra

ROOT = Path(__file__).resolve().parents[2]
SIZE = ["--leds", "2", "--rgb-cameras", "1", "--texels", "16", "--spp", "4", "--seed", "3"]
CALIBRATION = ["dome-calibration", "cal.capture.zarr", *SIZE, "--dark-frames", "2"]
RUN = ["dome-run", "run.capture.zarr", *SIZE, "--stage-positions", "1"]
FAST = ["--option", "stage.speed=3600", "--option", "lctf.settle_ms=1"]
SLOW = ["--option", "stage.speed=3600", "--option", "lctf.settle_ms=400"]  # a window to stop in
runner = CliRunner()


def spectwin(*arguments: str | Path) -> str:
    """Run ``spectwin`` in this process; its standard output."""
    result = runner.invoke(app, [str(argument) for argument in arguments])
    assert result.exit_code == 0, result.output
    return result.stdout


def start_lab(folder: Path, *options: str) -> subprocess.Popen:
    """``spectwin lab emulate --out folder`` in a process of its own, once its lab.yaml is
    written."""
    command = [sys.executable, "-m", "twin.cli.app", "lab", "emulate", "--out", str(folder)]
    process = subprocess.Popen(
        [*command, "--json", *options], cwd=ROOT, stdout=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 60
    while not (folder / "lab.yaml").exists():
        assert process.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)
    return process


def stop_lab(process: subprocess.Popen) -> dict:
    """Ctrl-C the emulated lab; the bytes exchanged with each device."""
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=30)
    assert process.returncode == 0
    return json.loads(out)["devices"]


def calibrate_and_process(folder: Path, calibration: Path | None = None) -> np.ndarray:
    """The run's spectral BTF (its reflectance), calibrated from the folder's calibration
    capture unless ``calibration`` is given."""
    if calibration is None:
        calibration = folder / "cal.npz"
        spectwin("calibrate", folder / "cal.capture.zarr", "--out", calibration, "--json")
    btf = folder / "run.btf.zarr"
    spectwin("process", folder / "run.capture.zarr", "--calibration", calibration, "--out", btf)
    return zarr.open_group(btf, mode="r")["reflectance"][...]


def capture(folder: Path, program: list[str], *options: str | Path) -> None:
    spectwin("capture", program[0], folder / program[1], *program[2:], *options, "--json")


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> Path:
    """The calibration and run on the twin's devices, processed."""
    folder = tmp_path_factory.mktemp("simulated")
    capture(folder, CALIBRATION)
    capture(folder, RUN)
    np.save(folder / "btf.npy", calibrate_and_process(folder))
    return folder


@pytest.fixture(scope="module")
def wired(tmp_path_factory) -> tuple[Path, dict]:
    """The same captures through the emulated lab, processed; and the bytes exchanged."""
    folder = tmp_path_factory.mktemp("wired")
    lab = start_lab(folder / "lab", *FAST)
    try:
        spectwin("lab", "check", folder / "lab" / "lab.yaml")
        capture(folder, CALIBRATION, "--devices", folder / "lab" / "lab.yaml")
        capture(folder, RUN, "--devices", folder / "lab" / "lab.yaml")
    finally:
        traffic = stop_lab(lab)
    np.save(folder / "btf.npy", calibrate_and_process(folder))
    return folder, traffic


def test_the_emulated_lab_captures_the_frames_and_btf_of_the_simulated_devices(simulated, wired):
    folder, traffic = wired
    for name in ("cal", "run"):
        twin = CaptureStore.open(simulated / f"{name}.capture.zarr")
        lab = CaptureStore.open(folder / f"{name}.capture.zarr")
        assert (twin.metadata.backend, lab.metadata.backend) == ("sim", "real")
        for camera in ("rgb00", "spectral"):
            np.testing.assert_array_equal(lab.frames(camera)[:], twin.frames(camera)[:])
    np.testing.assert_array_equal(np.load(folder / "btf.npy"), np.load(simulated / "btf.npy"))
    print("bytes exchanged with the emulated lab:", json.dumps(traffic, indent=2))
    assert set(traffic) == {"stage", "leds", "lctf"}
    for device in traffic.values():
        assert device["bytes_from_host"] > 0 and device["bytes_to_host"] > 0
    # 2 LEDs at one stage position: 198 slots, then the parameters, per switch at least
    assert traffic["leds"]["bytes_from_host"] > 10 * (198 + 5)


def _capture_until_a_frame_is_done(folder: Path, lab: Path) -> subprocess.Popen:
    """The run's capture in a process of its own, once it has taken a frame and not all."""
    command = [sys.executable, "-m", "twin.cli.app", "capture", *RUN[:1]]
    command += [str(folder / RUN[1]), *RUN[2:], "--devices", str(lab), "--json"]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    store, deadline = folder / RUN[1], time.monotonic() + 120
    while True:
        assert process.poll() is None and time.monotonic() < deadline, process.stderr
        try:
            pending = CaptureStore.open(store).pending_steps()
        except Exception:  # not created yet
            pending = None
        if pending is not None and 0 < len(pending) < len(CaptureStore.open(store).metadata.plan):
            return process
        time.sleep(0.02)


def test_a_killed_capture_resumes_through_the_lab_to_the_same_btf(simulated, wired, tmp_path):
    lab = start_lab(tmp_path / "lab", *SLOW)
    try:
        process = _capture_until_a_frame_is_done(tmp_path, tmp_path / "lab" / "lab.yaml")
        process.kill()
        process.wait()
        assert not CaptureStore.open(tmp_path / RUN[1]).complete
        spectwin("capture", "resume", tmp_path / RUN[1], "--devices", tmp_path / "lab" / "lab.yaml")
    finally:
        stop_lab(lab)
    btf = calibrate_and_process(tmp_path, wired[0] / "cal.npz")
    np.testing.assert_array_equal(btf, np.load(simulated / "btf.npy"))


def test_a_lab_unplugged_mid_capture_stops_it_resumably(simulated, wired, tmp_path):
    """The emulators stop (their ptys close) while the capture runs: it ends in one line that
    names the device and says how to continue; on a new lab it resumes to the same BTF."""
    first = start_lab(tmp_path / "lab", *SLOW)
    process = _capture_until_a_frame_is_done(tmp_path, tmp_path / "lab" / "lab.yaml")
    stop_lab(first)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 1
    [line] = stderr.decode().strip().splitlines()[-1:]
    assert line.startswith("error: a device kept failing (") and "cannot open /dev/pts" in line
    assert line.endswith(f"--devices {tmp_path / 'lab' / 'lab.yaml'}")
    assert "spectwin capture resume" in line
    second = start_lab(tmp_path / "lab2", *FAST)
    try:
        spectwin("capture", "resume", tmp_path / RUN[1], "--devices", tmp_path / "lab2/lab.yaml")
    finally:
        stop_lab(second)
    btf = calibrate_and_process(tmp_path, wired[0] / "cal.npz")
    np.testing.assert_array_equal(btf, np.load(simulated / "btf.npy"))


def test_lab_check_names_the_device_that_does_not_answer(tmp_path):
    """The GenICam camera of the simulated producer and the serial devices answer, a silent
    LED widget does not; after the lab stops, its ports are gone."""
    lab = start_lab(tmp_path / "lab", "--cameras", "genicam", "--option", "leds.silent=1")
    path = tmp_path / "lab" / "lab.yaml"
    try:
        saved = path.read_text()
        result = runner.invoke(app, ["lab", "check", str(path), "--json"])
    finally:
        stop_lab(lab)
    assert result.exit_code == 1
    checks = {found["role"]: found for found in json.loads(result.stdout)}
    assert {role for role, found in checks.items() if found["ok"]} == {
        "stage",
        "lctf",
        "spectral_camera",
    }
    assert checks["stage"]["model"] == "K10CR1" and checks["lctf"]["serial"] == "10218"
    assert checks["spectral_camera"]["model"] == "Machine Vision Games Ltd. Viky"
    assert all(checks[role]["round_trip_ms"] > 0 for role in ("stage", "lctf"))
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("error: leds (DMX USB Pro on /dev/pts/") and "did not answer" in line
    path.write_text(saved)  # the devices file of a lab that has stopped
    gone = runner.invoke(app, ["lab", "check", str(path)])
    assert gone.exit_code == 1
    assert gone.stderr.strip().startswith("error: stage (Thorlabs APT stage on /dev/pts/")
    assert "cannot open /dev/pts/" in gone.stderr and "No such file or directory" in gone.stderr
    assert gone.stderr.strip().endswith("(and 2 more)")  # the LEDs, the LCTF; the camera is there
