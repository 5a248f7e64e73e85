"""The spectwin command line end to end: info and the smoke render."""

import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from recon.spectral_exr import read_spectral_exr
from twin.cli import capture
from twin.cli.app import app
from twin.rigs.rig_config import load_rig

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
    assert summary["verdict"] == "PASS" and summary["tolerance"] == 0.03
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    for name in summary["outputs"]:
        assert (tmp_path / name).stat().st_size > 0
    image = read_spectral_exr(tmp_path / "colorchecker_qth.exr")
    assert image.cube.shape == (32, 48, 33) and np.all(np.isfinite(image.cube))


def test_smoke_rejects_bad_options(tmp_path):
    result = runner.invoke(app, ["smoke", "--out", str(tmp_path), "--spp", "0"])
    assert result.exit_code == 2
    assert "--spp" in result.stderr and "Traceback" not in result.output


def test_smoke_fails_with_exit_1_beyond_its_tolerance(tmp_path):
    """One sample per pixel cannot resolve the narrow LCTF bands: the render is far from the
    closed form, and the smoke test says so."""
    arguments = ["smoke", "--out", str(tmp_path), "--pixels-per-patch", "4", "--spp", "1"]
    result = runner.invoke(app, [*arguments, "--json"])
    assert result.exit_code == 1, result.output
    summary = json.loads(result.stdout)
    assert summary["verdict"] == "FAIL" and summary["max_abs_relative_error"] > 0.03
    (line,) = result.stderr.splitlines()
    assert line.startswith("error: smoke render FAIL") and "(tolerance 3 %)" in line


def test_camera_bench_test_reports_gain_noise_and_flicker(tmp_path):
    result = runner.invoke(app, ["camera", "coolsnap_k4", "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["measured_gain_dn_per_e"] == pytest.approx(0.2, rel=0.05)
    assert summary["measured_dark_noise_dn"] == pytest.approx(3.0, rel=0.1)
    assert (
        summary["flicker_spread_percent_at_50ms"]
        > 20 * summary["flicker_spread_percent_near_66_7ms"]
    )
    assert (tmp_path / "coolsnap_k4" / "camera_report.png").stat().st_size > 0


def test_camera_bench_test_names_unknown_cameras(tmp_path):
    result = runner.invoke(app, ["camera", "hasselblad", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "coolsnap_k4" in result.stderr and "Traceback" not in result.output


def test_estimate_gonio_reports_a_total_that_is_the_sum_of_its_printed_parts():
    """Thesis 4.1.1's sum: pairs x (exposures + 33 x switching + settle) + moves. The thesis's
    134.9 h is a calibration target, checked once in tests/twin/rigs/test_rig_geometry.py."""
    result = runner.invoke(app, ["estimate", "gonio", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    timing = load_rig("gonio").timing
    pairs = summary["pairs"]
    assert pairs == 6561 == summary["lamp_runs"]["position_a"] + summary["lamp_runs"]["position_b"]
    assert sum(summary["band_exposures_s"].values()) == pytest.approx(
        summary["exposure_per_pair_s"], abs=0.01
    )
    assert summary["per_pair_capture_s"] == pytest.approx(
        summary["exposure_per_pair_s"] + 33 * timing.switch_and_download_s, abs=0.002
    )
    # The printed parts are rounded to 1 ms: the sum agrees within a few seconds of ~5 days.
    parts_s = pairs * (summary["per_pair_capture_s"] + timing.settle_s)
    assert summary["total_s"] == pytest.approx(
        parts_s + (pairs - 1) * summary["mean_move_s"], abs=10
    )
    assert summary["total_h"] == pytest.approx(summary["total_s"] / 3600, abs=0.01)


def test_gallery_writes_a_frame_of_every_material_in_every_rig(tmp_path):
    result = runner.invoke(app, ["gallery", "--out", str(tmp_path), "--pixels", "64", "--spp", "4"])
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "gallery.json").read_text())
    assert len(summary["outputs"]) == 12
    for name in summary["outputs"]:
        assert (tmp_path / name).stat().st_size > 0


def test_camchar_study_recovers_the_camera_from_a_glossy_chart_under_a_spot(tmp_path):
    result = runner.invoke(app, ["camchar-study", "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["fields"] == 113
    # Highlights and the spot's fall-off break the basic model; the extended one copes.
    assert min(summary["rmse_basic"]) > 0.15
    assert max(summary["rmse_extended"]) < 0.08
    for name in summary["outputs"]:
        assert (tmp_path / name).stat().st_size > 0


def test_camchar_study_names_bad_scenarios(tmp_path):
    result = runner.invoke(app, ["camchar-study", "--out", str(tmp_path), "--light", "candle"])
    assert result.exit_code == 2
    assert "daylight" in result.stderr and "Traceback" not in result.output


def test_camchar_cameras_characterizes_a_measured_camera_left_out_of_its_prior(tmp_path):
    arguments = ["--camera", "Canon PowerShot S90", "--out", str(tmp_path), "--json"]
    result = runner.invoke(app, ["camchar-cameras", *arguments])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["cameras"] == 1 and summary["seed"] == 0
    # The camera least like the others (measured 4.2 % with prior, 5.5 % without, 9.6 % Jiang).
    errors = {method: summary["methods"][method]["max_pct"] for method in summary["methods"]}
    assert errors["prior"] < errors["extended"] < errors["jiang2013"]
    assert errors["prior"] < 7.0
    for name in summary["outputs"]:
        assert (tmp_path / name).stat().st_size > 0
    table = (tmp_path / "table.csv").read_text().splitlines()
    assert table[0].startswith("camera,prior_error_pct") and table[1].startswith("Canon")


def test_capture_dry_run_then_capture_then_refuse_to_overwrite(tmp_path):
    store = tmp_path / "demo.capture.zarr"
    dry = runner.invoke(app, ["capture", "demo", str(store), "--dry-run", "--json"])
    assert dry.exit_code == 0, dry.output
    assert json.loads(dry.output)["steps"] == 72 and not store.exists()
    done = runner.invoke(app, ["capture", "demo", str(store), "--json"])
    assert done.exit_code == 0, done.output
    assert json.loads(done.output)["complete"] is True
    again = runner.invoke(app, ["capture", "demo", str(store)])
    assert again.exit_code == 2 and "exists" in again.stderr
    assert "spectwin capture resume" in again.stderr


def test_dry_run_counts_the_pairs_whose_marks_leave_the_window(tmp_path):
    """The holder's marks span 53 mm, 68 px of the 256 across the camera's 20 cm field seen
    head-on, and registration refines each corner in a piece a tenth of that wide around it:
    a 64 px window cuts into them in every pair of the reduced sampling, a 96 px window in the
    pairs that see the square's diagonal across the frame, a 128 px window in none."""
    counted = {}
    for window in (64, 96, 128):
        dry = runner.invoke(
            app,
            ["capture", "gonio-run", str(tmp_path / "run.capture.zarr")]
            + ["--dry-run", "--pixels", "256", "--window", str(window), "--json"],
        )
        assert dry.exit_code == 0, dry.output
        summary = json.loads(dry.output)
        counted[window] = summary["pairs_with_marks_outside_window"]
        # (68 px + a tenth) x sqrt(2), the diagonal of the square with its pieces: 106 px
        assert summary["window_px_holding_marks"] == 106
    assert counted[64] == 156 and 0 < counted[96] < 156 and counted[128] == 0


def test_a_ctrl_c_as_a_finished_capture_returns_says_how_far_it_got(tmp_path, monkeypatch):
    """A Ctrl-C that arrives after the capture's last frame, as the command returns (here: as
    its context closes), ends with exit 130 and the line saying the capture is complete."""
    captured = capture._capture

    def capture_then_ctrl_c_at_close(ctx, *args, **kwargs):
        def ctrl_c():
            raise KeyboardInterrupt

        ctx.call_on_close(ctrl_c)
        return captured(ctx, *args, **kwargs)

    monkeypatch.setattr(capture, "_capture", capture_then_ctrl_c_at_close)
    result = runner.invoke(app, ["capture", "demo", str(tmp_path / "demo.capture.zarr"), "--json"])
    assert result.exit_code == 130
    assert result.stderr.splitlines() == [
        "interrupted after 72 of 72 frames; the capture is complete"
    ]


def test_a_low_spp_render_prints_no_library_warning(tmp_path):
    # Mitsuba's low-discrepancy sampler warns (in colour codes, on the process's stdout) when it
    # rounds a sample count: spectwin asks it for counts it takes as they are.
    result = subprocess.run(
        [sys.executable, "-m", "twin.cli.app", "smoke", "--out", str(tmp_path)]
        + ["--pixels-per-patch", "8", "--spp", "20", "--json"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    output = result.stdout + result.stderr
    assert "WARN" not in output and "Warning" not in output, output[-2000:]
    assert json.loads(result.stdout)["spp"] == 64  # 20 rounded up to the next power of 4
