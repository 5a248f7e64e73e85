"""``spectwin demo`` at tiny size: every stage runs and the report shows every figure."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from twin.cli.app import app
from twin.studies.demo import DemoSettings, run_demo

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


@pytest.fixture(scope="module")
def tiny_demo(tmp_path_factory):
    """One tiny demo run shared by the tests of this module: its folder, metrics and stages."""
    out = tmp_path_factory.mktemp("tiny") / "demo"
    stages = []
    metrics = run_demo(out, TINY, step=stages.append)
    return out, metrics, stages


def test_tiny_demo_writes_the_report_with_every_figure_and_finite_metrics(tiny_demo):
    out, metrics, stages = tiny_demo
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


def test_the_report_prints_rounded_numbers_with_units(tiny_demo):
    out, metrics, _ = tiny_demo
    page = (out / "report.html").read_text()
    cells = re.findall(r"<tr><td>(.*?)</td><td>(.*?)</td></tr>", page)
    assert len(cells) == len(metrics["headline"]) >= 8
    for name, value in cells:
        # At most 4 significant digits: no float printed in full.
        mantissa = value.lstrip("-").split("e")[0].replace(".", "").lstrip("0")
        assert float(value) == float(value) and len(mantissa) <= 4, (name, value)
        # Every quantity names its unit in brackets, or is a ratio or Delta E.
        assert re.search(r"\((%|s|px|h)\)$", name) or "ratio" in name or "Delta E" in name, name
    text = re.sub(r"<[^>]*>", " ", page)
    for number in re.findall(r"\d*\.\d+", text):
        assert len(number.replace(".", "").lstrip("0")) <= 4, number


@pytest.mark.skipif(
    not (Path("/usr/bin/chromium").exists() and Path("/usr/bin/chromedriver").exists()),
    reason="needs Debian's chromium and chromium-driver (make test's bootstrap installs them)",
)
def test_the_report_loads_in_a_real_browser_with_every_image_and_no_console_error(
    tiny_demo, tmp_path
):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    out, _, _ = tiny_demo
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1400,2400",
        f"--user-data-dir={tmp_path / 'profile'}",
    ):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        driver.get((out / "report.html").as_uri())
        images = driver.execute_script(
            "return Array.from(document.images).map("
            "i => [i.getAttribute('src'), i.complete && i.naturalWidth > 0])"
        )
        driver.save_screenshot(str(out / "report.png"))
        console = driver.get_log("browser")
    finally:
        driver.quit()
    assert len(images) == 8 and all(loaded for _, loaded in images), images
    assert [entry for entry in console if entry["level"] == "SEVERE"] == []
    assert (out / "report.png").stat().st_size > 50_000
