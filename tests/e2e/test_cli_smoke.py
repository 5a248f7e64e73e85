"""The spectwin command line end to end: info and the smoke render."""

import json

import numpy as np
from typer.testing import CliRunner

from recon.spectral_exr import read_spectral_exr
from twin.cli import app

runner = CliRunner()


def test_info_reports_the_variant_as_json():
    result = runner.invoke(app, ["info", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["variant"].endswith("spectral") and report["threads"] >= 1


def test_smoke_render_writes_checked_outputs(tmp_path):
    result = runner.invoke(
        app, ["smoke", "--out", str(tmp_path), "--pixels-per-patch", "8", "--spp", "128", "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["image_px"] == [32, 48] and summary["bands"] == 33
    assert summary["max_abs_relative_error"] < 0.03
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    for name in summary["outputs"]:
        assert (tmp_path / name).stat().st_size > 0
    image = read_spectral_exr(tmp_path / "colorchecker_qth.exr")
    assert image.cube.shape == (32, 48, 33) and np.all(np.isfinite(image.cube))


def test_smoke_rejects_bad_options(tmp_path):
    result = runner.invoke(app, ["smoke", "--out", str(tmp_path), "--spp", "0"])
    assert result.exit_code != 0
    assert "spp" in result.output
