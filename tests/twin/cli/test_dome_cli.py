"""``spectwin dome-study`` end to end at the smallest size (8 texels, the colour checker, without
the dome captures, whose store path ``tests/twin/studies/test_dome_study_stores.py`` covers): the
printed JSON is the metrics file, and every figure is written."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from recon.scheduling.dome_schedule import THESIS_RGB_EXPOSURES_S
from twin.cli.app import app

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
            "--analytic-only",
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
    # Exposure totals against quantities known without the study: the thesis's HDR RGB set
    # once (one image) plus the plan's 30 band exposures times each hybrid's scale. The plan
    # summed by the schedule comes from the 1 px per texel setup, the hybrids from the 2 px one
    # (its own noisy calibration): measured 48.17 s against 48.12 s, 0.11 % apart.
    rgb_set_s = sum(THESIS_RGB_EXPOSURES_S)
    band_sum_s = printed["schedules"]["band_exposures_sum_s"]
    assert printed["schedules"]["rgb_set_s"] == pytest.approx(rgb_set_s, rel=1e-12)
    assert [h["scale"] for h in exposure["hybrid"]] == pytest.approx([1.0, 0.25, 1 / 12])
    spectral_s = [h["spectral_s"] for h in exposure["hybrid"]]
    for hybrid in exposure["hybrid"]:
        assert hybrid["spectral_s"] == pytest.approx(hybrid["scale"] * band_sum_s, rel=3e-3)
        assert hybrid["spectral_s"] == pytest.approx(hybrid["scale"] * spectral_s[0], rel=1e-12)
        assert hybrid["total_s"] - hybrid["spectral_s"] == pytest.approx(rgb_set_s, rel=1e-12)
    reference_s = exposure["spectral_only_totals_s"][0]
    np.testing.assert_allclose(
        exposure["spectral_only_totals_s"], reference_s / np.array([1, 4, 16, 64]), rtol=1e-12
    )


def test_store_summary_prints_the_shift_at_a_fixed_view():
    """The printed summary of the store path: per camera that carried the band data in one of
    the two processings, its images' mean errors with and without them ("none" where no texel
    was kept), next to the with / without line and the 10.5 totals."""
    from twin.cli.dome import _store_summary

    errors = {
        "with_spectral_data": {"mean_relative_error_pct": 7.48},
        "without_spectral_data": {"mean_relative_error_pct": 8.8},
    }
    shift = {
        "rgb05": {
            "mean_relative_error_pct": {"with": 7.48, "without": 8.82},
            "mean_delta_e94": {"with": 1.5, "without": 1.54},
        },
        "rgb00": None,
    }
    source = errors | {"edge_free": errors}
    stores = {
        "materials": {
            "colorchecker16": {
                "stores": source,
                "analytic": source,
                "view_fixed_shift": {
                    "stores": {"edge_free": shift},
                    "analytic": {"edge_free": shift},
                },
            }
        },
        "exposure_10_5": {
            "reference_total_s": 1826.6,
            "hybrid_total_s": 51.52,
            "orders_of_magnitude": 1.5496,
        },
    }
    summary = _store_summary(stores)
    line = summary["colorchecker16 same view, edge-free: with / without bands (stores)"]
    assert line == "rgb05 7.48 / 8.82 %, rgb00 none"
    assert summary["colorchecker16 dome stores: with / without bands (stores)"] == "7.48 % / 8.80 %"
    assert summary["10.5 from the stores"] == "1827 s / 51.5 s, 1.55 orders of magnitude"
