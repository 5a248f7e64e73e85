"""``spectwin capture dome-calibration|dome-run`` and ``spectwin estimate dome``: dry runs write
nothing, options of other programs are unknown options, ``spectwin capture resume`` reads the
store's settings.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from hwbridge.store import CaptureStore
from recon.errors import InputError
from twin.cli.app import app
from twin.dome.programs import (
    DomeCaptureSize,
    dome_plan_parts,
    dome_run_program,
)
from twin.kinds.dome import DomeRunSettings
from twin.kinds.registry import capture_program
from twin.rigs.rig_config import load_rig

runner = CliRunner()
REDUCED = ["--stage-positions", "2", "--leds", "24", "--rgb-cameras", "3"]


def test_a_dry_run_of_the_reduced_dome_run_counts_its_frames_and_writes_nothing(tmp_path):
    store = tmp_path / "out" / "lego.capture.zarr"
    arguments = ["capture", "dome-run", str(store), "--material", "lego", *REDUCED]
    arguments += ["--texels", "64", "--dry-run", "--json"]
    result = runner.invoke(app, arguments)
    assert result.exit_code == 0, result.output
    plan = json.loads(result.stdout)
    schedule = dome_plan_parts(load_rig("dome"), DomeCaptureSize(2, 24, 3)).exposures.schedule
    spectral = 2 + sum(len(schedule[k % len(schedule)]) for k in range(2 * 24))
    rgb = 2 * (1 + 24 * 4)  # an alignment frame per position, the HDR set per LED
    assert plan["frames"] == {"rgb00": rgb, "rgb05": rgb, "rgb10": rgb, "spectral": spectral}
    assert plan["kinds"] == {"alignment": 2 * 4, "sample": 3 * rgb + spectral - 2 * 4}
    # per position: the alignment (all LEDs) per camera, then the LEDs in passes per camera
    # (24 LEDs: one pass of each camera, the spectral camera's of each LED's scheduled bands)
    assert plan["renders"] == 2 * (4 + 3 + 1) and plan["led_renders"] == "pose"
    single = runner.invoke(app, [*arguments, "--led-renders", "single"])
    assert json.loads(single.stdout)["renders"] == 2 * (4 + 24 * 4)  # per LED and camera
    assert plan["frame_size"] == "264 x 264 px" and plan["stage_positions"] == 2
    assert plan["estimated_duration_s"] > 48 * sum((0.05, 0.186, 0.666, 2.5))
    assert list(tmp_path.iterdir()) == []


def test_a_dry_run_of_the_calibration_takes_200_darks_per_spectral_exposure(tmp_path):
    store = tmp_path / "cal.capture.zarr"
    arguments = ["dome-calibration", str(store), "--leds", "24", "--rgb-cameras", "3"]
    result = runner.invoke(app, ["capture", *arguments, "--dry-run", "--json"])
    assert result.exit_code == 0, result.output
    plan = json.loads(result.stdout)
    exposures = dome_plan_parts(load_rig("dome"), DomeCaptureSize(24, 24, 3)).exposures
    times = {*exposures.band_s, *exposures.spectral_series_s, exposures.all_leds_s["spectral"]}
    rgb_darks = 3 * 16 * (4 + 1)  # per camera, 16 per HDR exposure and the all-LED one
    assert plan["kinds"]["dark"] == 200 * len(times) + rgb_darks
    assert plan["kinds"]["geometric"] == 9 * 4  # flat + 8 wedge orientations, 4 cameras
    assert not store.exists()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["dome-run", "--pixels", "64"], "No such option: --pixels"),
        (["dome-calibration", "--stage-positions", "2"], "No such option: --stage-positions"),
        (["dome-run", "--dark-frames", "5"], "No such option: --dark-frames"),
        (["gonio-run", "--leds", "5"], "No such option: --leds"),
        (["dome-run", "--material", "nosuch"], "material: expected one of"),
    ],
)
def test_options_a_dome_program_does_not_use_are_refused(tmp_path, arguments, message):
    program, *options = arguments
    result = runner.invoke(
        app,
        ["capture", program, str(tmp_path / "x.capture.zarr"), *options],
        prog_name="spectwin",
    )
    assert result.exit_code == 2, result.output
    assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr
    if message.startswith("No such option"):  # the help that lists the program's options
        assert f"(see 'spectwin capture {program} --help')" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_sizes_the_rig_cannot_take_are_refused():
    with pytest.raises(InputError, match="leds: expected 1..198"):
        dome_run_program(size=DomeCaptureSize(leds=199))
    with pytest.raises(InputError, match="texels: expected 4..1024"):
        dome_run_program(size=DomeCaptureSize(texels=2))
    with pytest.raises(InputError, match="fault_rate"):
        dome_run_program(fault_rate=2.0)


@pytest.mark.render
def test_resume_of_a_dome_run_reads_its_settings_and_takes_no_others(tmp_path):
    path = tmp_path / "run.capture.zarr"
    program = dome_run_program("lego", size=DomeCaptureSize(1, 3, 1, 8, 4), seed=5)
    settings = SessionSettings(rig=program.rig, backend="sim", seed=5)
    with locked_session_store(path, program.plan, program.devices(), settings) as store:
        capture_steps(store, range(2), program.devices(5, range(2)))  # the alignment frames
    kind, stored = capture_program(CaptureStore.open(path))
    assert (kind.name, stored.name) == ("dome", "dome-run")
    assert stored.stored(CaptureStore.open(path)) == DomeRunSettings(
        seed=5,
        material="lego",
        stage_positions=1,
        leds=3,
        rgb_cameras=1,
        texels=8,
        spp=4,
        led_renders="pose",
    )
    for option, value in [
        ("--leds", "5"),
        ("--texels", "16"),
        ("--material", "wallpaper"),
        ("--program", "dome-calibration"),
        ("--pixels", "64"),
        ("--led-renders", "single"),
    ]:
        result = runner.invoke(app, ["capture", "resume", str(path), option, value])
        assert result.exit_code == 2, (option, result.output)
        assert f"No such option: {option}" in result.stderr, result.stderr
        assert result.stderr.count("\n") == 1, result.stderr
    resumed = runner.invoke(app, ["capture", "resume", str(path), "--json"])
    assert resumed.exit_code == 0, resumed.output
    summary = json.loads(resumed.stdout)
    assert summary["complete"] and summary["program"] == "dome-run"
    assert sum(summary["frames"].values()) == len(program.plan)
    assert CaptureStore.open(path).pending_steps() == []


def test_estimate_dome_prints_the_plans_times_against_the_thesis():
    result = runner.invoke(app, ["estimate", "dome", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["leds"] == 198 and summary["stage_positions"] == 24
    assert summary["thesis_rgb_set_s"] == summary["rgb_set_s"]
    assert summary["thesis_exposure_increase_pct"] == 61.0
    assert summary["run_h"] > summary["rgb_only_h"] > 24 * 198 * 3.402 / 3600
