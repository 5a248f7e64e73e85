"""Sweep files: design points from parameter paths, and bad files refused before anything runs."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from recon.errors import InputError
from twin.cli.app import app
from twin.kinds.registry import sweep_kind
from twin.studies.sweep_file import SweepRange, check_points, load_sweep
from twin.studies.sweep_report import pareto_front

BASE = {
    "name": "test sweep",
    "rig": "gonio",
    "plan": {"pixels": 64, "texels": 16},
    "parameters": {"rig.lamps.*.spectrum": ["hmi", "qth"]},
}


def _write(tmp_path: Path, **changes) -> Path:
    document = {**BASE, **changes}
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def test_builtin_gonio_sweep_is_the_product_of_its_parameters():
    sweep = load_sweep("gonio_lamp_filter_sampling", sweep_kind)
    assert len(sweep.points) == 2 * 3 * 3
    expected = itertools.product(["hmi", "qth"], ["VS-07", "VS-10", "VS-20"], [5, 9, 13])
    for point, (lamp, filter_model, directions) in zip(sweep.points, expected, strict=True):
        assert [lamp.spectrum for lamp in point.rig.lamps] == [lamp, lamp]
        assert point.rig.camera.filter == filter_model
        assert sum(count for _, count in point.plan.rings) == directions
        assert point.plan.pixels == 128 and point.material == "colorchecker16"
    # Every design has its own folder key; the untouched rig fields are the rig file's.
    assert len({point.key for point in sweep.points}) == len(sweep.points)
    assert sweep.points[0].rig.rail.radius_m == 2.0
    assert sweep.points[17].label == "qth, VS-20, 13 directions"


def test_builtin_dome_sweep_varies_schedule_exposure_and_filter():
    sweep = load_sweep("dome_schedule_tbase_filter", sweep_kind)
    assert sweep.kind == "dome" and len(sweep.points) == 3 * 2 * 3
    point = sweep.points[-1]
    assert (point.plan.schedule_images, point.plan.longest_band_s) == (12, 5.48)
    assert point.plan.target_relative_noise == 0.08 and point.plan.leds == 12
    assert point.label == "schedule_images 12, longest_band_s 5.48, target_relative_noise 0.08"
    assert set(sweep.objectives) <= set(sweep.measures)


def test_a_range_gives_evenly_spaced_values(tmp_path):
    assert SweepRange(start=0.6, stop=0.9, num=4).values() == pytest.approx([0.6, 0.7, 0.8, 0.9])
    assert SweepRange(start=64, stop=128, step=32).values() == [64, 96, 128]
    path = _write(
        tmp_path,
        parameters={"rig.exposure.white_fill": {"start": 0.6, "stop": 0.8, "num": 3}},
    )
    fills = [point.rig.exposure.white_fill for point in load_sweep(path, sweep_kind).points]
    assert fills == pytest.approx([0.6, 0.7, 0.8])


BAD_FILES = [
    ({"parameters": {"rig.camera.filtr": ["VS-10"]}}, "rig.camera.filtr: unknown key 'filtr'"),
    ({"parameters": {"rig.lamps.5.spectrum": ["hmi"]}}, "'5' is not an item of a list of 2"),
    ({"parameters": {"plan.bands": [33]}}, "plan.bands: unknown plan field"),
    ({"parameters": {"camera.gain": [1]}}, "expected a path starting with 'rig.' or 'plan.'"),
    ({"parameters": {"rig.camera.filter": []}}, "rig.camera.filter: empty list of values"),
    (
        {"parameters": {"plan.pixels": {"start": 128, "stop": 64, "num": 2}}},
        "plan.pixels: empty range: stop 64.0 is below start 128.0",
    ),
    ({"parameters": {"rig.camera.filter": ["VS-15"]}}, "camera.filter: Input should be"),
    ({"parameters": {"rig.exposure.white_fill": [1.5]}}, "exposure.white_fill: Input should be"),
    ({"parameters": {"plan.pixels": [100000]}}, "pixels: Input should be less than"),
    ({"parameters": {"plan.pixels": [3000]}}, "pixels: expected 1..2048 pixels"),
    ({"parameters": {"plan.rings": [[[0, 3]]]}}, "one direction at 0"),
    ({"parameters": {"material": ["velvet"]}}, "material: expected one of"),
    ({"objectives": ["capture_time_h", "speed"]}, "objectives: expected two different"),
    ({"plan": {"pixel": 64}}, "plan: unknown field 'pixel'"),
    ({"rig": "dome", "plan": {}}, "unknown key 'lamps'"),
    (
        {"rig": "dome", "parameters": {"plan.leds": [10]}, "plan": {"rings": [[0, 1]]}},
        "plan: unknown field 'rings'",
    ),
    ({"rig": "dome", "plan": {}, "parameters": {"plan.leds": [0]}}, "leds: Input should be"),
    (
        {"rig": "dome", "plan": {}, "parameters": {"plan.longest_band_s": [-1.0]}},
        "longest_band_s: Input should be greater than 0",
    ),
    (
        {"rig": "dome", "plan": {}, "parameters": {"plan.stage_positions": [30]}},
        "stage_positions: Input should be less than or equal to 24",
    ),
    (
        {"rig": "dome", "plan": {"leds": 6}, "parameters": {"plan.schedule_images": [8]}},
        "schedule_images: expected at most plan.leds (6) images, got 8",
    ),
    (
        {"rig": "dome", "plan": {}, "parameters": {"plan.longest_band_s": [2.74]}},
        "no schedule of 35 band exposures in 10 images keeps every image within",
    ),
    (
        {"rig": "dome", "plan": {}, "parameters": {"rig.led_rings.0.count": [7]}},
        "led_count: the rings hold 199 LEDs, not 198",
    ),
]


@pytest.mark.parametrize(("changes", "phrase"), BAD_FILES, ids=[p for _, p in BAD_FILES])
def test_bad_sweep_files_are_refused_naming_the_problem(tmp_path, changes, phrase):
    with pytest.raises(InputError) as error:
        sweep = load_sweep(_write(tmp_path, **changes), sweep_kind)
        check_points(sweep, sweep_kind(sweep.kind).check)
    assert phrase in str(error.value)


def test_the_command_refuses_a_bad_sweep_before_it_writes_anything(tmp_path):
    path = _write(tmp_path, parameters={"rig.camera.filter": ["VS-10", "VS-30"]})
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["sweep", str(path), "--out", str(out)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "point 1" in lines[0]
    assert "Traceback" not in result.output and not out.exists()


def test_pareto_front_keeps_exactly_the_non_dominated_designs(rng):
    assert pareto_front(np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 3.0], [4.0, 1.0]])).tolist() == [
        True,
        True,
        False,
        True,
    ]
    # Equal designs do not dominate each other.
    assert pareto_front(np.array([[1.0, 1.0], [1.0, 1.0], [2.0, 2.0]])).tolist() == [
        True,
        True,
        False,
    ]
    # On a circle's lower-left quarter every point is on the front; shifted copies never are.
    angles = rng.uniform(np.pi, 1.5 * np.pi, 40)
    arc = np.column_stack([np.cos(angles), np.sin(angles)])
    mask = pareto_front(np.vstack([arc, arc + 0.01]))
    assert mask[:40].all() and not mask[40:].any()
