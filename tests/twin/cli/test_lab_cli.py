"""Bad devices files: ``spectwin capture ... --devices`` and ``spectwin lab check`` refuse each in
one line naming the file, the role and what was expected, and write nothing."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from twin.cli.app import app

runner = CliRunner()

DOME = "rig: dome\ndevices:\n"
GOOD_DOME = {
    "stage": "apt://",
    "leds": "dmxusbpro://",
    "lctf": "varispec://",
    "spectral_camera": "sim",
    "rgb_cameras": "sim",
}


def dome(**roles: str | None) -> str:
    """A dome devices file with ``roles`` changed (``None``: left out)."""
    merged = {**GOOD_DOME, **roles}
    lines = [f"  {role}: {value}" for role, value in merged.items() if value is not None]
    return DOME + "\n".join(lines) + "\n"


BAD_FILES = [
    (None, "devices file: no file"),
    ("rig: dome\ndevices: [\n", "not YAML at line"),
    ("- stage\n- leds\n", "expected the keys rig and devices"),
    ("rig: dome\n", "expected the keys rig and devices, got ['rig']"),
    ("rig: robot\ndevices: {}\n", "rig: expected one of dome, gonioreflectometer, got 'robot'"),
    ("rig: dome\ndevices: /dev/ttyUSB0\n", "devices: expected a mapping of role: device"),
    (dome(camera2="sim"), "devices.camera2: unknown role of the dome; expected stage, leds"),
    (dome(lctf=None), "devices.lctf: missing; expected sim, a serial port or a varispec:// URL"),
    (dome(stage="ttyUSB0"), "devices.stage.port: 'ttyUSB0' is not a serial port; expected"),
    (dome(stage="varispec://"), "a varispec:// URL is not a Thorlabs APT stage"),
    (dome(stage="{port: apt://, speed: 3}"), "devices.stage.speed: unknown setting; expected"),
    (dome(leds="{port: COM3, first_address: 0}"), "devices.leds.first_address: Input should"),
    (dome(stage="{port: apt://, counts_per_deg: -1}"), "counts_per_deg: Input should be greater"),
    (dome(spectral_camera="{producer: cam.dll}"), "cam.dll is not a GenTL producer; expected"),
    (dome(spectral_camera="{serial: '12'}"), "devices.spectral_camera.producer: Field required"),
    (dome(rgb_cameras="{rgb11: sim}"), "devices.rgb_cameras.rgb11: no such RGB camera"),
    (dome(rgb_cameras="{rgb00: /dev/ttyUSB3}"), "devices.rgb_cameras.rgb00: expected sim, or a"),
    (dome(leds="5"), "devices.leds: expected sim, a serial port or a dmxusbpro:// URL, got 5"),
    (dome(spectrometer="sim"), "devices.spectrometer: expected a spectrometer's serial"),
    (
        "rig: gonioreflectometer\ndevices: {camera: sim, lctf: sim, monitor: sim, "
        "positioner: /dev/ttyUSB0, lamp: sim}\n",
        "devices.positioner: expected sim (the robot and rail have no driver)",
    ),
    (
        "rig: gonioreflectometer\ndevices: {camera: sim, lctf: sim, monitor: sim, "
        "positioner: sim, lamp: sim}\n",
        "is a devices file of the gonioreflectometer; dome-calibration runs on the dome",
    ),
]


@pytest.mark.parametrize(("text", "message"), BAD_FILES)
def test_a_bad_devices_file_is_refused_before_anything_is_written(tmp_path, text, message):
    lab = tmp_path / "lab.yaml"
    if text is not None:
        lab.write_text(text)
    store = tmp_path / "out" / "cal.capture.zarr"
    arguments = ["capture", "dome-calibration", str(store), "--devices", str(lab)]
    result = runner.invoke(app, [*arguments, "--leds", "2", "--rgb-cameras", "1"])
    assert result.exit_code == 2, result.output
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("error: ") and message in line, line
    assert not (tmp_path / "out").exists()
    if "dome-calibration" not in message:  # a file for the other rig is a good file
        checked = runner.invoke(app, ["lab", "check", str(lab)])
        assert checked.exit_code == 2 and checked.stderr.strip() == line


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--workers", "2"], "--workers is not used with --devices"),
        (["--fault-rate", "0.01"], "--fault-rate is not used with --devices"),
    ],
)
def test_what_a_lab_cannot_do_is_refused(tmp_path, options, message):
    (tmp_path / "lab.yaml").write_text(dome())
    store = tmp_path / "out" / "cal.capture.zarr"
    arguments = ["capture", "dome-calibration", str(store), "--devices", str(tmp_path / "lab.yaml")]
    result = runner.invoke(app, [*arguments, *options])
    assert result.exit_code == 2 and message in result.stderr
    assert not (tmp_path / "out").exists()


def test_a_lab_of_simulated_devices_has_nothing_to_check(tmp_path):
    (tmp_path / "lab.yaml").write_text(
        dome(stage="sim", leds="sim", lctf="sim").replace("dmxusbpro://", "sim")
    )
    result = runner.invoke(app, ["lab", "check", str(tmp_path / "lab.yaml")])
    assert result.exit_code == 2 and "every role is sim" in result.stderr


def test_emulator_settings_are_checked_before_a_lab_starts(tmp_path):
    result = runner.invoke(app, ["lab", "emulate", "--out", str(tmp_path), "--option", "stage"])
    assert result.exit_code == 2 and "expected ROLE.KEY=VALUE" in result.stderr
    result = runner.invoke(
        app, ["lab", "emulate", "--out", str(tmp_path), "--option", "camera.speed=3"]
    )
    assert result.exit_code == 2 and "the dome emulates no camera" in result.stderr
    result = runner.invoke(
        app, ["lab", "emulate", "--out", str(tmp_path), "--option", "stage.colour=red"]
    )
    assert result.exit_code == 2 and "options.stage: unknown ['colour']" in result.stderr
    assert not (tmp_path / "lab.yaml").exists()
