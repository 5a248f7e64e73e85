"""``spectwin dome-study`` end to end at the smallest size (8 texels, the colour checker): the
printed JSON is the metrics file, and every figure is written."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from twin.cli import app

FIGURES = (
    "fig10_5_plan.png",
    "fig10_7_single_image_errors.png",
    "fig10_9_spectra.png",
    "fig10_13_multi_image.png",
    "fig10_23_comparison.png",
    "fig10_4_cross_check.png",
    "exposure_vs_error.png",
)


def test_dome_study_prints_its_metrics_as_json(tmp_path):
    result = CliRunner().invoke(
        app,
        [
            "dome-study",
            "--out",
            str(tmp_path),
            "--texels",
            "8",
            "--material",
            "colorchecker16",
            "--json",
        ],
        catch_exceptions=False,
    )
    assert result.exit_code == 0, result.output
    printed = json.loads(result.output)
    assert printed == json.loads((tmp_path / "dome_study.json").read_text())
    for name in FIGURES:
        assert (tmp_path / name).stat().st_size > 10_000, name
    exposure = printed["exposure_10_5"]
    assert exposure["pixels_per_texel"] == 2
    hybrid = exposure["hybrid"][0]
    assert np.isclose(
        hybrid["reference_over_hybrid"], exposure["reference_total_s"] / hybrid["total_s"]
    )
