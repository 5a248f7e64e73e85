"""``spectwin camchar PHOTO...``: a camera characterized from real chart photographs (thesis
chapter 9) against its measured response, on photographs made from measurements (a camera
outside the default prior, ``tests.recon.chart_photos.synthetic``) and on the real llanos2019
capture (a Flea3 behind seven band-pass filters, thesis 9.4 with several lights); and every bad
input refused in one line, exit 2, nothing written.
"""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy import io
from typer.testing import CliRunner

from recon.measured_data import data_path
from tests.recon.chart_photos import synthetic
from twin.cli.app import app

runner = CliRunner()

LLANOS = data_path("real/llanos2019")
FILTER_COLUMNS = {
    400: "400 nm",
    450: "442 nm",
    500: "500 nm",
    550: "550 nm",
    600: "600 nm",
    650: "650 nm",
    700: "700 nm",
}
"""The band in a frame's name and the filter's column in spectra_averaged.csv."""
LLANOS_CORNERS = "28,27;384,26;361,247;51,240"
"""The chart's corners in the 408 x 342 frames, from the patch label map (a homography through
the 24 patches' centroids, residual 0.6 px at most)."""


def llanos_arguments() -> list[str]:
    """``spectwin camchar`` on the 49 chart frames of llanos2019 (the README's command)."""
    arguments = []
    folder = LLANOS / "captured_images" / "images_filtered_light" / "color_checker"
    for frame in sorted(folder.glob("*.tif")):
        match = re.search(r"_(\d+)nm_(\d+)ms_", frame.name)
        assert match is not None
        band, exposure_ms = (int(value) for value in match.groups())
        light = f"{LLANOS / 'spectral_data' / 'spectra_averaged.csv'}:{FILTER_COLUMNS[band]}"
        arguments += [str(frame), "--light", light, "--exposure-s", str(exposure_ms / 1000)]
    return [
        *arguments,
        "--chart",
        str(LLANOS / "colorchecker_asd.csv"),
        "--layout",
        "4x6",
        "--corners",
        LLANOS_CORNERS,
        "--bayer",
        "gbrg",
        "--encoding",
        "linear",
        "--truth",
        str(LLANOS / "flea3_filter_white_balance.csv"),
    ]


def _run(arguments: list[str]):
    return runner.invoke(app, ["camchar", *arguments], prog_name="spectwin")


def test_camchar_characterizes_a_raw_and_a_tiff_under_two_lights(tmp_path):
    """A DNG under D65 and a 16-bit TIFF under A of the Nikon D100 (isetbio's measurement, not
    among the prior's cameras): measured 4.6 % of the peak against its measured response."""
    raw = synthetic.write_dng(tmp_path / "d65.dng", "D65")
    tiff = synthetic.write_tiff(tmp_path / "a.tif", synthetic.rgb_image("A", peak=30000.0))
    truth = synthetic.write_truth(tmp_path / "d100.csv")
    out = tmp_path / "out"
    arguments = [str(raw), str(tiff), "--light", "D65", "--light", "A"]
    arguments += ["--corners", synthetic.CORNERS_TEXT, "--truth", str(truth), "--out", str(out)]
    result = _run([*arguments, "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["lights"] == ["D65", "A"] and summary["prior"] == "51 measured cameras"
    assert summary["truth_curve_worst_pct"] < 5.0
    assert summary["truth_per_light_worst_pct"] < 0.3
    assert summary["residual_max_pct"] < 3.0
    assert any("raw mosaic, black level 512" in note for note in summary["photo_notes"])
    for name in summary["outputs"]:
        assert (out / name).stat().st_size > 0
    response = np.loadtxt(out / "response.csv", delimiter=",", skiprows=1)
    assert response.shape == (41, 4) and response[:, 1:].max() == 1.0
    assert response[np.argmax(response[:, 3]), 0] < response[np.argmax(response[:, 1]), 0]
    with (out / "patches.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 48 and rows[0]["name"] == "dark skin"
    # Without the prior: measured 5.5 %.
    result = _run([*arguments[:-2], "--out", str(tmp_path / "plain"), "--no-prior", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["truth_curve_worst_pct"] > summary["truth_curve_worst_pct"]


def test_camchar_finds_the_colorchecker_itself(tmp_path):
    tiff = synthetic.write_tiff(tmp_path / "chart.tif", synthetic.rgb_image())
    out = tmp_path / "out"
    result = _run([str(tiff), "--light", "D65", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.stdout
    summary = json.loads((out / "summary.json").read_text())
    corners = np.array(summary["corners"][str(tiff)])
    assert np.abs(corners - synthetic.CORNERS).max() < 16  # measured 12.6 px
    assert summary["residual_max_pct"] < 3.0


def test_camchar_on_the_llanos2019_capture_against_the_measured_flea3(tmp_path):
    """Real chapter 9: the Flea3 from its own 49 chart frames through the seven filters (ASD
    measurements of the patches and filters), against ``sensor.mat``'s R/G and B/G per filter.

    Measured: worst channel 7.35 % of the largest ratio (R; B 3.78 %), 4.7 s. The goal of 5 %
    is not reached, and these frames cannot reach it: their own white patch's R/G and B/G under
    the seven filters are 7.8 % (R) from ``sensor.mat``, whose author fitted it also to a capture
    of another day with the filters held by hand again (``captured_images/about.txt``).
    """
    out = tmp_path / "out"
    result = _run([*llanos_arguments(), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert len(summary["photographs"]) == 49 and len(summary["lights"]) == 7
    assert summary["photo_notes"] == ["8-bit values taken as linear"]
    errors = summary["truth_per_light_rmse_pct"]
    assert errors[0] < 8.0 and errors[1] == 0.0 and errors[2] < 4.5
    # The white patch (19) as the frames see it, merged over the exposures.
    with (out / "patches.csv").open() as handle:
        white = np.array(
            [
                [float(row[f"rgb_{c}"]) for c in "RGB"]
                for row in csv.DictReader(handle)
                if row["patch"] == "19"
            ]
        )
    ratios = white / white[:, 1:2]
    measured = io.loadmat(LLANOS / "multispectral_images" / "sensor.mat")["sensor_map_relative"].T
    floor = np.sqrt(np.mean((ratios - measured) ** 2, axis=0)).max() / measured.max()
    assert floor > 0.07
    # The 650 nm filter: R/G 9.9 estimated, 10.1 in the frames, 8.7 in sensor.mat.
    response = np.loadtxt(out / "response.csv", delimiter=",", skiprows=1)
    assert response[np.argmax(response[:, 1]), 0] == pytest.approx(600, abs=20)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("camchar_inputs")
    image = synthetic.rgb_image()
    paths = {
        "TIFF": synthetic.write_tiff(folder / "chart.tif", image),
        "MOSAIC": synthetic.write_tiff(folder / "mosaic.tif", synthetic.mosaic(image)),
        "TIFF8": synthetic.write_tiff(folder / "chart8.tif", image / 160, np.uint8),
        "CLIPPED": synthetic.write_tiff(folder / "clipped.tif", 100 * image),
        "JPEG": folder / "chart.jpg",
        "PLAIN": folder / "plain.txt",
        "OUT": folder / "out",
    }
    paths["JPEG"].write_bytes(b"\xff\xd8\xff\xe0 not really")
    paths["PLAIN"].write_text("a file")
    spectra = {
        "NAN_LIGHT": "wavelength_nm,lamp\n380,1\n500,nan\n780,1\n",
        "NARROW_LIGHT": "wavelength_nm,lamp\n500,1\n550,1\n600,1\n",
        "NEGATIVE_LIGHT": "wavelength_nm,lamp\n380,1\n500,-0.5\n780,1\n",
        "CHART_CSV": "wavelength_nm,a,b,c\n380,0.5,0.2,0.1\n780,0.5,0.2,0.1\n",
        "NARROW_TRUTH": "wavelength_nm,R,G,B\n450,1,1,1\n650,1,1,1\n",
        "BALANCE": "light,R,G,B\nA,1,1,1\n",
    }
    for name, text in spectra.items():
        paths[name] = folder / f"{name.lower()}.csv"
        paths[name].write_text(text)
    return paths


CORNERS = ["--corners", synthetic.CORNERS_TEXT]
PROBES: list[tuple[list[str], str]] = [
    (["@JPEG", "--light", "D65", *CORNERS], "JPEG is lossy and gamma-encoded"),
    (["@TIFF8", "--light", "D65", *CORNERS], "an 8-bit image, most likely gamma-encoded (sRGB)"),
    (["@TIFF", "--light", "D65", "--corners", "150,120;760,150;740,940;130,500"], "lies outside"),
    (["@TIFF", "--light", "D65", "--corners", "1,2;3,4"], "expected four points"),
    (["@TIFF", "--light", "D65", "--corners", "150,120;740,540;760,150;130,500"], "not a convex"),
    (["@TIFF", "--light", "@NAN_LIGHT", *CORNERS], "line 3: NaN or infinity"),
    (["@TIFF", "--light", "@NARROW_LIGHT", *CORNERS], "covers 500-600 nm; expected spectra"),
    (["@TIFF", "--light", "@NEGATIVE_LIGHT", *CORNERS], "expected a non-negative spectrum"),
    (["@TIFF", "--light", "D65", *CORNERS, "--truth", "@NARROW_TRUTH"], "covers 450-650 nm"),
    (["@TIFF", "--light", "D65", *CORNERS, "--truth", "@BALANCE"], "no row for the lights"),
    (["@TIFF", "--light", "D65", "--chart", "sg", *CORNERS], "expected one of ['colorchecker']"),
    (["@TIFF", "--light", "D65", "--chart", "@CHART_CSV", *CORNERS], "needs --layout"),
    (
        ["@TIFF", "--light", "D65", "--chart", "@CHART_CSV", "--layout", "4x6", *CORNERS],
        "3 patches; expected 24",
    ),
    (["@TIFF", "--light", "D65", "--chart", "@CHART_CSV", "--layout", "1x3"], "finds only"),
    (["@TIFF", "--light", "D65", "--layout", "4by6", *CORNERS], "the colorchecker is 4x6"),
    (["@TIFF", "--light", "candle", *CORNERS], "expected a CIE illuminant such as 'D65'"),
    (["@TIFF", "@TIFF", "@TIFF", "--light", "A", "--light", "D65"], "given 2 times for 3"),
    (["@TIFF", *CORNERS], "--light: expected the light of the photographs"),
    (["@MOSAIC", "--light", "D65", *CORNERS], "expected its Bayer pattern"),
    (["@CLIPPED", "--light", "D65", *CORNERS], "clipped in R in every exposure"),
    (["@TIFF", "--light", "D65", "--exposure-s", "-1", *CORNERS], "one positive time"),
    (["@TIFF", "--light", "D65", "--exposure-s", "0", *CORNERS], "one positive time"),
    (["@TIFF", "--light", "D65", "--encoding", "gamma", *CORNERS], "'gamma' is not one of"),
    (["nosuch.tif", "--light", "D65", *CORNERS], "nosuch.tif: no such file"),
    (["@TIFF", "--light", "D65", *CORNERS, "--out", "@PLAIN"], "is a file; expected a folder"),
]


def _arguments(arguments: list[str], paths: dict[str, Path]) -> list[str]:
    return [str(paths[a[1:]]) if a.startswith("@") else a for a in arguments]


@pytest.mark.parametrize(("arguments", "phrase"), PROBES, ids=[p[1][:40] for p in PROBES])
def test_bad_input_is_one_line_exit_2_and_nothing_written(inputs, arguments, phrase):
    given = _arguments(arguments, inputs)
    if "--out" not in given:
        given += ["--out", str(inputs["OUT"])]
    result = _run(given)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert phrase in lines[0]
    assert not inputs["OUT"].exists()


def test_the_option_choices_are_those_of_the_reader():
    from recon.chart_photos.images import BAYER_PATTERNS
    from recon.image_files import ENCODINGS
    from twin.cli.camchar import Bayer
    from twin.cli.choices import Encoding

    assert tuple(Bayer) == BAYER_PATTERNS and tuple(Encoding) == ENCODINGS
