"""``spectwin capture PROGRAM``: a dry run of every program writes nothing, settings that cannot
work leave no store, and ``spectwin capture resume`` continues with the program and settings of
the store (it takes none of its own)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from hwbridge.store import CaptureStore
from recon.calibration.gonio import GonioCalibration
from recon.errors import InputError
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app
from twin.gonio.capture import (
    gonio_calibration_program,
    gonio_measurement_program,
    run_gonio_measurement,
)
from twin.gonio.sim_session import demo_program, run_demo_session
from twin.kinds.gonio import GonioRunSettings
from twin.kinds.registry import capture_program

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
        (["demo"], 72, "32 x 32 px"),
        (["gonio-calibration"], 591, "64 x 64 px"),
        (["gonio-run"], 5213, "256 x 256 px"),  # the rig model's exposures
        (
            ["gonio-run", "--calibration", "@CAL", "--pixels", "96"]
            + ["--window", "64", "--material", "lego", "--spp", "4"],
            5189,  # one exposure for every band: 8 dark frames, not 32
            "64 x 64 px",
        ),
        # Sattler's 57 directions to 60 degrees: 3192 pairs x 33 bands + darks and white
        (
            ["gonio-run", "--sampling", "glossy", "--window", "64"],
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
    program, *options = [str(calibration) if a == "@CAL" else a for a in arguments]
    result = runner.invoke(app, ["capture", program, str(store), "--dry-run", "--json", *options])
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
    with pytest.raises(InputError, match=message):
        build()


def test_a_refused_capture_leaves_no_store_behind(tmp_path):
    store = tmp_path / "run.capture.zarr"
    with pytest.raises(InputError, match="spp"):
        run_gonio_measurement(store, EXPOSURES_S, spp=-3)
    with pytest.raises(InputError, match="window"):
        run_gonio_measurement(store, EXPOSURES_S, pixels=32, window=64)
    with pytest.raises(InputError, match="fault_rate"):
        run_demo_session(store, 0, fault_rate=2.0)
    assert list(tmp_path.iterdir()) == []
    result = runner.invoke(app, ["capture", "gonio-run", str(store), "--spp", "0"])
    assert result.exit_code == 2 and "'--spp'" in result.stderr
    assert list(tmp_path.iterdir()) == []


def _one_line(result, code: int, message: str) -> None:
    assert result.exit_code == code, result.output
    assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr


def test_resume_continues_with_the_seed_and_program_of_the_store(tmp_path):
    path = tmp_path / "seven.capture.zarr"
    _partial(path, demo_program(7), 20)
    refused = runner.invoke(app, ["capture", "resume", str(path), "--seed", "3"])
    _one_line(refused, 2, "No such option: --seed")  # the seed is the store's
    resumed = runner.invoke(app, ["capture", "resume", str(path), "--json"])
    assert resumed.exit_code == 0, resumed.output
    assert json.loads(resumed.stdout)["program"] == "demo"
    reference = run_demo_session(tmp_path / "reference.capture.zarr", 7)
    np.testing.assert_array_equal(
        CaptureStore.open(path).frames("k4")[:], reference.frames("k4")[:]
    )
    other = tmp_path / "other.capture.zarr"
    _partial(other, demo_program(7), 5)
    resumed = runner.invoke(app, ["capture", "resume", str(other), "--json"])
    assert resumed.exit_code == 0, resumed.output  # the store's seed 7
    np.testing.assert_array_equal(
        CaptureStore.open(other).frames("k4")[:], reference.frames("k4")[:]
    )


def test_resume_of_a_run_reads_its_settings_and_takes_no_others(tmp_path, calibration):
    path = tmp_path / "run.capture.zarr"
    program = gonio_measurement_program(
        EXPOSURES_S, material="lego", pixels=64, window=48, spp=4, seed=5
    )
    _partial(path, program, 3)  # dark frames only: nothing rendered
    kind, stored = capture_program(CaptureStore.open(path))
    assert (kind.name, stored.name) == ("gonioreflectometer", "gonio-run")
    assert stored.stored(CaptureStore.open(path)) == GonioRunSettings(
        seed=5,
        material="lego",
        pixels=64,
        window=48,
        sampling="reduced",
        spp=4,
        exposures_s=tuple(EXPOSURES_S),
    )
    probes = [
        (["--pixels", "128"], "No such option: --pixels"),
        (["--window", "32"], "No such option: --window"),
        (["--spp", "16"], "No such option: --spp"),
        (["--sampling", "glossy"], "No such option: --sampling"),
        (["--material", "wallpaper"], "No such option: --material"),
        (["--seed", "0"], "No such option: --seed"),
        (["--program", "demo"], "No such option: --program"),
        (["--calibration", str(calibration)], "No such option: --calibration"),
        (["--fault-rate", "0.01"], "--fault-rate is not used by gonio-run; leave it out"),
    ]
    for arguments, message in probes:
        result = runner.invoke(app, ["capture", "resume", str(path), *arguments])
        _one_line(result, 2, message)
    assert CaptureStore.open(path).pending_steps() == list(range(3, len(program.plan)))


def test_the_capture_renders_at_the_rigs_sample_count_unless_told(tmp_path):
    """Without --spp each program renders at its own default (the gonio's stratified 16, the
    dome's 64); a given --spp is what the plan renders at."""
    from twin.dome.programs import DEFAULT_SPP
    from twin.gonio.render import GONIO_SPP

    assert gonio_measurement_program(EXPOSURES_S).rig.spp == GONIO_SPP
    dome = ["--leds", "2", "--rgb-cameras", "1", "--texels", "8"]
    for arguments, spp in [
        (["gonio-run"], GONIO_SPP),
        (["gonio-run", "--spp", "40"], 40),
        (["dome-run", *dome, "--stage-positions", "1"], DEFAULT_SPP),
        (["dome-calibration", *dome, "--spp", "9"], 9),
    ]:
        store = tmp_path / "x.capture.zarr"
        program, *options = arguments
        result = runner.invoke(
            app, ["capture", program, str(store), "--dry-run", "--json", *options]
        )
        assert result.exit_code == 0, result.output
        assert json.loads(result.stdout)["spp"] == spp, arguments


def test_the_dry_run_names_the_pairs_that_will_not_register_and_the_pixels_that_do(tmp_path):
    store = tmp_path / "run.capture.zarr"
    result = runner.invoke(
        app, ["capture", "gonio-run", str(store), "--dry-run", "--pixels", "64", "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["pairs_unlikely_to_register"] == "156 pairs: 0-155"
    assert summary["pairs_that_may_not_register"] == "none"
    assert summary["pixels_registering_every_pair"] == 215
    table = runner.invoke(app, ["capture", "gonio-run", str(store), "--dry-run", "--pixels", "128"])
    assert "pairs unlikely to register" in table.stdout and "215" in table.stdout
    assert not store.exists()


def test_a_capture_whose_pairs_will_not_register_says_so_in_one_line(
    tmp_path, calibration, monkeypatch
):
    from twin.gonio.capture import CaptureProgram

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(CaptureProgram, "run", interrupted)  # the warning comes before it runs
    arguments = ["capture", "gonio-run", str(tmp_path / "run.capture.zarr")]
    arguments += ["--calibration", str(calibration), "--pixels", "64"]
    result = runner.invoke(app, arguments)
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert warnings == [
        "warning: 156 of 156 pairs are unlikely to register at --pixels 64: their registration "
        "marks are under 1.3 px wide (narrowest 0.63 px); --pixels 215 or more registers every "
        "pair"
    ]
    settled = runner.invoke(
        app,
        ["capture", "gonio-run", str(tmp_path / "other.capture.zarr")]
        + ["--calibration", str(calibration), "--pixels", "256"],
    )
    assert "warning:" not in settled.stderr
