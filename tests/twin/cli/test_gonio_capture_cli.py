"""``spectwin capture``: a dry run of every program writes nothing, settings that cannot work
leave no store, and --resume continues with the program and settings of the store."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from hwbridge.store import CaptureStore
from recon.calibration.gonio import GonioCalibration
from recon.errors import SpectwinInputError
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app
from twin.gonio.capture import (
    gonio_calibration_program,
    gonio_measurement_program,
    run_gonio_measurement,
)
from twin.gonio.sim_session import demo_program, run_demo_session

runner = CliRunner()
EXPOSURES_S = np.full(DEFAULT_GRID.size, 2 / 15)


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "cal.json"
    GonioCalibration.identity(EXPOSURES_S, DEFAULT_GRID.wavelengths_nm, 1 / 15).save(path)
    return path


def _partial(path, program, steps: int) -> None:
    """Capture the first ``steps`` steps of ``program`` into a new store (a capture cut short)."""
    settings = SessionSettings(rig=program.rig, backend="sim", seed=program.seed)
    with locked_session_store(path, program.plan, program.devices(), settings) as store:
        capture_steps(store, range(steps), program.devices(program.seed, range(steps)))


@pytest.mark.parametrize(
    ("arguments", "steps", "frame_size"),
    [
        (["--program", "demo"], 72, "32 x 32 px"),
        (["--program", "gonio-calibration"], 591, "64 x 64 px"),
        (["--program", "gonio-run"], 5213, "256 x 256 px"),  # the rig model's exposures
        (
            ["--program", "gonio-run", "--calibration", "@CAL", "--pixels", "96"]
            + ["--window", "64", "--material", "lego", "--spp", "4"],
            5189,  # one exposure for every band: 8 dark frames, not 32
            "64 x 64 px",
        ),
        # Sattler's 57 directions to 60 degrees: 3192 pairs x 33 bands + darks and white
        (
            ["--program", "gonio-run", "--sampling", "glossy", "--window", "64"],
            105401,
            "64 x 64 px",
        ),
    ],
    ids=["demo", "gonio-calibration", "gonio-run-modelled", "gonio-run", "gonio-run-glossy"],
)
def test_a_dry_run_of_every_program_prints_the_plan_and_writes_nothing(
    tmp_path, calibration, arguments, steps, frame_size
):
    store = tmp_path / "out" / "x.capture.zarr"
    arguments = [str(calibration) if a == "@CAL" else a for a in arguments]
    result = runner.invoke(app, ["capture", str(store), "--dry-run", "--json", *arguments])
    assert result.exit_code == 0, result.output
    plan = json.loads(result.stdout)
    assert plan["steps"] == steps and plan["frames"] == {"k4": steps}
    assert plan["frame_size"] == frame_size
    assert sum(plan["kinds"].values()) == steps
    assert plan["estimated_duration_s"] > sum(plan["kinds"].values()) * 0.13
    height, width = (int(n) for n in frame_size.split(" px")[0].split(" x "))
    assert plan["storage_mb"] > steps * height * width * 2 / 1e6
    assert list(tmp_path.iterdir()) == []  # not the store, its folder or a lock


def test_the_dry_run_duration_is_the_rig_timing_of_the_plan():
    """The demo: 6 darks and 2 x 33 band frames at 2/15 s, 0.13 s switch and download each,
    two views (one move between them) with 1 s settling after each."""
    program = demo_program(0)
    plan = program.dry_run()
    exposures = sum(step["exposure_s"] for step in program.plan)
    from twin.gonio.capture_time import move_seconds
    from twin.rigs.rig_config import load_rig

    config = load_rig("gonio")
    move = move_seconds(program.poses[0], program.poses[1], config)
    expected = exposures + 72 * 0.13 + 2 * 1.0 + move
    assert plan["estimated_duration_s"] == pytest.approx(expected)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: gonio_measurement_program(EXPOSURES_S, spp=-3), "spp: expected at least 1"),
        (
            lambda: gonio_measurement_program(EXPOSURES_S, pixels=32, window=64),
            "window: expected a read-out window of 1..32 pixels",
        ),
        (lambda: gonio_measurement_program(EXPOSURES_S, pixels=4096), "pixels: expected 1..2048"),
        (lambda: gonio_measurement_program(EXPOSURES_S, pixels=0), "pixels: expected 1..2048"),
        (lambda: gonio_measurement_program(EXPOSURES_S, material="nosuch"), "material"),
        (
            lambda: gonio_measurement_program(np.full(DEFAULT_GRID.size, 700.0)),
            "outside the Photometrics CoolSNAP K4's range 0.001..600 s",
        ),
        (lambda: gonio_measurement_program(EXPOSURES_S, seed=-1), "seed: expected"),
        (lambda: gonio_calibration_program(spp=0), "spp: expected at least 1"),
        (lambda: gonio_calibration_program(pixels=3000), "pixels: expected 1..2048"),
        (lambda: gonio_calibration_program(white_fill=1.5), "white_fill"),
        (lambda: demo_program(0, fault_rate=1.5), r"fault_rate: expected a probability in \[0, 1"),
        (lambda: demo_program(0, fault_rate=float("nan")), "fault_rate"),
        (lambda: demo_program(-2), "seed: expected"),
    ],
)
def test_settings_that_cannot_work_are_refused_before_anything_is_made(build, message):
    with pytest.raises(SpectwinInputError, match=message):
        build()


def test_a_refused_capture_leaves_no_store_behind(tmp_path):
    store = tmp_path / "run.capture.zarr"
    with pytest.raises(SpectwinInputError, match="spp"):
        run_gonio_measurement(store, EXPOSURES_S, spp=-3)
    with pytest.raises(SpectwinInputError, match="window"):
        run_gonio_measurement(store, EXPOSURES_S, pixels=32, window=64)
    with pytest.raises(SpectwinInputError, match="fault_rate"):
        run_demo_session(store, 0, fault_rate=2.0)
    assert list(tmp_path.iterdir()) == []
    result = runner.invoke(app, ["capture", str(store), "--program", "gonio-run", "--spp", "0"])
    assert result.exit_code == 2 and "'--spp'" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_resume_continues_with_the_seed_and_program_of_the_store(tmp_path):
    path = tmp_path / "seven.capture.zarr"
    _partial(path, demo_program(7), 20)
    refused = runner.invoke(app, ["capture", str(path), "--resume", "--seed", "3"])
    assert refused.exit_code == 2
    assert "was captured with --seed 7, not 3" in refused.stderr
    agreeing = runner.invoke(app, ["capture", str(path), "--resume", "--seed", "7", "--json"])
    assert agreeing.exit_code == 0, agreeing.output  # the store's value, given: fine
    reference = run_demo_session(tmp_path / "reference.capture.zarr", 7)
    np.testing.assert_array_equal(
        CaptureStore.open(path).frames("k4")[:], reference.frames("k4")[:]
    )
    other = tmp_path / "other.capture.zarr"
    _partial(other, demo_program(7), 5)
    resumed = runner.invoke(app, ["capture", str(other), "--resume", "--json"])
    assert resumed.exit_code == 0, resumed.output  # no --seed: the store's 7
    np.testing.assert_array_equal(
        CaptureStore.open(other).frames("k4")[:], reference.frames("k4")[:]
    )


def test_resume_of_a_run_reads_its_settings_and_refuses_other_ones(tmp_path, calibration):
    path = tmp_path / "run.capture.zarr"
    program = gonio_measurement_program(
        EXPOSURES_S, material="lego", pixels=64, window=48, spp=4, seed=5
    )
    _partial(path, program, 3)  # dark frames only: nothing rendered
    other_plan = tmp_path / "other.json"
    GonioCalibration.identity(
        np.full(DEFAULT_GRID.size, 3 / 15), DEFAULT_GRID.wavelengths_nm, 1 / 15
    ).save(other_plan)
    probes = [
        (["--pixels", "128"], "was captured with --pixels 64, not 128"),
        (["--window", "32"], "was captured with --window 48, not 32"),
        (["--spp", "16"], "was captured with --spp 4, not 16"),
        (["--sampling", "glossy"], "was captured with --sampling reduced, not glossy"),
        (["--material", "wallpaper"], "was captured with --material lego, not wallpaper"),
        (["--seed", "0"], "was captured with --seed 5, not 0"),
        (["--program", "demo"], "was captured with --program gonio-run, not demo"),
        (["--calibration", str(other_plan)], "plans other band exposures than the store's run"),
        (["--fault-rate", "0.01"], "--fault-rate is not used by --program gonio-run"),
    ]
    for arguments, message in probes:
        result = runner.invoke(app, ["capture", str(path), "--resume", *arguments])
        assert result.exit_code == 2, (arguments, result.output)
        assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr
    assert CaptureStore.open(path).pending_steps() == list(range(3, len(program.plan)))


def test_the_capture_renders_at_the_rigs_sample_count_unless_told(tmp_path):
    """Without --spp each program renders at its own default (the gonio's stratified 16, the
    dome's 64); a given --spp is what the plan renders at."""
    from twin.dome.programs import DEFAULT_SPP
    from twin.gonio.render import GONIO_SPP

    assert gonio_measurement_program(EXPOSURES_S).rig["spp"] == GONIO_SPP
    dome = ["--leds", "2", "--rgb-cameras", "1", "--texels", "8"]
    for arguments, spp in [
        (["--program", "gonio-run"], GONIO_SPP),
        (["--program", "gonio-run", "--spp", "40"], 40),
        (["--program", "dome-run", *dome, "--stage-positions", "1"], DEFAULT_SPP),
        (["--program", "dome-calibration", *dome, "--spp", "9"], 9),
    ]:
        store = tmp_path / "x.capture.zarr"
        result = runner.invoke(app, ["capture", str(store), "--dry-run", "--json", *arguments])
        assert result.exit_code == 0, result.output
        assert json.loads(result.stdout)["spp"] == spp, arguments
