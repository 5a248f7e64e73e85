"""``spectwin demo`` at tiny size: every stage runs and the report shows every figure."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from twin.cli import app
from twin.demo import DemoSettings, run_demo

pytestmark = pytest.mark.render

TINY = DemoSettings(
    rings=((0.0, 1), (30.0, 2)),
    pixels=256,
    texels=48,
    spp=32,
    figure_pixels=32,
    figure_spp=16,
    map_height=8,
    texture_texels=16,
)


def test_tiny_demo_writes_the_report_with_every_figure_and_finite_metrics(tmp_path):
    out = tmp_path / "demo"
    stages = []
    metrics = run_demo(out, TINY, step=stages.append)
    assert stages == [
        "calibration session",
        "measurement run",
        "processing and compression",
        "evaluation against the truth",
        "spectralization",
        "validation rendering",
    ]
    assert json.loads((out / "metrics.json").read_text())["headline"] == metrics["headline"]
    page = (out / "report.html").read_text()
    for figure in (
        "lamps_filter.png",
        "exposure_plan.png",
        "raw_frames.png",
        "textures.png",
        "evaluation.png",
        "spectralization.png",
        "validation/figure46.png",
        "validation/spectrophotometer_45_0.png",
    ):
        assert f'src="{figure}"' in page and (out / figure).stat().st_size > 10_000
    assert all(np.isfinite(value) for value in metrics["headline"].values())
    # Even at this size the BTF and the spectralization are accurate.
    assert metrics["gonio_evaluation"]["mean_relative_error_matte_fields_pct"] < 3.0
    assert metrics["gonio_evaluation"]["max_corner_error_px"] < 0.25
    assert metrics["spectralization"]["mean_relative_error_pct"] < 5.0
    assert (out / ".spectwin-demo").exists()  # marks the folder as the demo's to replace


def test_demo_refuses_a_folder_it_did_not_write(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path)])
    assert result.exit_code == 2 and "not written by spectwin demo" in result.output
    assert (tmp_path / "notes.txt").read_text() == "mine"
