"""``spectwin twin-vs-real``: a run on the shipped llanos2019 bench (one filter, small renders),
and bad benches and options refused with one line, exit 2 (usage) or 1 (data that does not fit
together), and nothing written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from recon.measured_data import data_path
from twin.cli.app import app
from twin.rigs.bench_config import BENCH_DIR

runner = CliRunner()
PATCHES = yaml.safe_load((BENCH_DIR / "llanos2019.yaml").read_text())["chart"]["patches"]


def test_twin_vs_real_on_one_filter_writes_the_report_and_figures(tmp_path):
    out = tmp_path / "report"
    result = runner.invoke(
        app,
        ["twin-vs-real", "llanos2019", "--band", "550", "--spp", "8", "--out", str(out), "--json"],
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["frames"] == 7 and report["dark_frames"] == 14
    assert set(report["split"]["fit_exposure_ms_per_band"]) == {"550"}
    assert report["mean_error"]["all"]["n"] > 100
    assert report["mean_error"]["all"]["median"] < 0.25
    assert report["clipping"]["agreement"] >= 0.95
    assert [row["role"] for row in report["dark"]].count("fit") == 3
    assert json.loads((out / "report.json").read_text())["bench"] == report["bench"]
    header = (out / "patches.csv").read_text().splitlines()[0]
    assert header.startswith("band_nm,exposure_ms,patch,channel,role,measured_mean_dn")
    for name in report["figures"]:
        assert (out / name).stat().st_size > 10_000


def _bench_file(tmp_path: Path, **changes) -> Path:
    """The shipped llanos2019 bench, its data given by absolute path, with ``changes`` (a
    ``section__key`` name changes a key of a section; a value of None removes the key)."""
    document = yaml.safe_load((BENCH_DIR / "llanos2019.yaml").read_text())
    document["data"] = str(data_path("real/llanos2019"))
    for name, value in changes.items():
        target, key = (
            (document[name.split("__")[0]], name.split("__")[1])
            if "__" in name
            else (document, name)
        )
        if value is None:
            target.pop(key)
        else:
            target[key] = value
    path = tmp_path / "bench.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


BAD_BENCHES = [
    ({"extra": 1}, 2, "extra: Extra inputs are not permitted"),
    ({"camera": None}, 2, "camera: Field required"),
    (
        {"fit__patches": ["white 9.5 (.05 D)", "nosuch"]},
        2,
        "['nosuch'] are not among chart.patches",
    ),
    ({"fit__min_dn": 250}, 2, "expected min_dn below max_dn"),
    ({"data": "/nonexistent/bench"}, 2, "data folder /nonexistent/bench does not exist"),
    ({"chart__labels": "nosuch.png"}, 2, "chart.labels"),
    ({"mapping": "nosuch"}, 2, "mapping: no file"),
    ({"camera": "nosuch"}, 2, "camera: no file"),
    ({"camera": "coolsnap_k4"}, 2, "needs a colour camera"),
    ({"filters__columns": {550: "nosuch"}}, 1, "expected a 'Wavelength' column and ['nosuch']"),
    ({"chart__patches": list(PATCHES[1:])}, 1, "image labelling patches 1-23"),
    ({"reduction__width": 400}, 1, "expected a 342x400 image labelling patches"),
    ({"focal_length_mm": -8}, 2, "focal_length_mm: Input should be greater than 0"),
]


@pytest.mark.parametrize(
    ("changes", "code", "phrase"), BAD_BENCHES, ids=lambda value: str(value)[:40]
)
def test_a_bad_bench_is_refused_with_one_line(tmp_path, changes, code, phrase):
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["twin-vs-real", str(_bench_file(tmp_path, **changes)), "--out", str(out)]
    )
    assert result.exit_code == code, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    assert phrase in lines[0]
    assert not out.exists()


BAD_OPTIONS = [
    (["nosuch"], 2, "expected a path or one of ['llanos2019']"),
    (
        ["llanos2019", "--band", "123"],
        2,
        "bands: expected some of [400, 450, 500, 550, 600, 650, 700] nm",
    ),
    (["llanos2019", "--spp", "0"], 2, "'--spp'"),
    (["llanos2019", "--seed", "-1"], 2, "'--seed'"),
    (["@MALFORMED"], 2, "malformed YAML"),
    (["llanos2019", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
]


@pytest.mark.parametrize(
    ("arguments", "code", "phrase"), BAD_OPTIONS, ids=lambda value: str(value)[:40]
)
def test_bad_options_are_refused_with_one_line(tmp_path, arguments, code, phrase):
    (tmp_path / "plain").write_text("a file")
    (tmp_path / "malformed.yaml").write_text("name: [unclosed\n")
    places = {"@PLAIN": str(tmp_path / "plain"), "@MALFORMED": str(tmp_path / "malformed.yaml")}
    arguments = [places.get(argument, argument) for argument in arguments]
    if "--out" not in arguments:
        arguments += ["--out", str(tmp_path / "out")]
    result = runner.invoke(app, ["twin-vs-real", *arguments])
    assert result.exit_code == code, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and phrase in lines[0], result.output
    assert not (tmp_path / "out").exists()
