"""``spectwin btf export`` and ``spectwin btf import`` at the command line: a round trip that
keeps every bit, and one-line refusals (a BTF store made by hand: 3 pairs of 6 x 6 texels)."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from recon.btf.store import BTFStore, write_btf
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app

runner = CliRunner()


def _run(*arguments):
    return runner.invoke(app, [str(argument) for argument in arguments], prog_name="spectwin")


def _one_line_error(result, code: int) -> str:
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def test_export_and_import_round_trip_and_refusals(tmp_path):
    values = np.random.default_rng(0).random((3, 6, 6, DEFAULT_GRID.size), np.float32)
    directions = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]])
    source = write_btf(
        tmp_path / "a.btf.zarr",
        values,
        DEFAULT_GRID,
        light_dirs=directions,
        view_dirs=directions[::-1],
        material="lego",
    )
    exported = _run("btf", "export", source.path, "--out", tmp_path / "slices", "--json")
    assert exported.exit_code == 0, exported.output
    assert json.loads(exported.stdout)["pairs"] == 3
    imported = _run(
        "btf", "import", tmp_path / "slices", "--out", tmp_path / "b.btf.zarr", "--json"
    )
    assert imported.exit_code == 0, imported.output
    assert json.loads(imported.stdout)["complete"] is True
    copy = BTFStore.open(tmp_path / "b.btf.zarr")
    np.testing.assert_array_equal(copy.read().view(np.uint32), values.view(np.uint32))
    assert copy.material == "lego"

    again = _run("btf", "import", tmp_path / "slices", "--out", tmp_path / "b.btf.zarr")
    assert "exists" in _one_line_error(again, 2)
    busy = _run("btf", "export", source.path, "--out", tmp_path / "slices")
    assert "new or empty folder" in _one_line_error(busy, 2)
    empty = tmp_path / "empty"
    empty.mkdir()
    missing = _run("btf", "import", empty, "--out", tmp_path / "c.btf.zarr")
    assert "no directions.json" in _one_line_error(missing, 2)
    assert not (tmp_path / "c.btf.zarr").exists()
