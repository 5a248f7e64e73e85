"""Camera characterization from chart photographs (``recon.chart_photos``): reading photographs
as linear signal, sampling the patches, merging exposures, finding the chart, and the estimate
of a measured camera outside the default prior against its measurement."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import tifffile

from recon.chart_photos.characterize import ChartPhotograph, characterize_photographs
from recon.chart_photos.charts import chart_from_csv, named_chart
from recon.chart_photos.detect import detect_colorchecker
from recon.chart_photos.images import read_photo
from recon.chart_photos.lights import light_spectrum
from recon.chart_photos.patches import merge_exposures, sample_patches
from recon.chart_photos.truth import MeasuredResponse, truth_errors
from recon.errors import InputError
from tests.recon.chart_photos import synthetic


def test_a_dng_reads_as_its_raw_mosaic_less_the_black_level(tmp_path):
    path = synthetic.write_dng(tmp_path / "chart.dng")
    photo = read_photo(path)
    stored = tifffile.imread(path).astype(float)
    assert photo.channel_index is not None
    assert photo.channel_index[:2, :2].tolist() == [[0, 1], [1, 2]]  # RGGB, no demosaicing
    np.testing.assert_array_equal(photo.values, stored - synthetic.BLACK_LEVEL)
    assert photo.white_level == synthetic.WHITE_LEVEL - synthetic.BLACK_LEVEL


def test_a_16_bit_png_keeps_its_bits_and_its_channel_order(tmp_path):
    image = np.zeros((8, 8, 3), np.uint16)
    image[..., 0], image[..., 1], image[..., 2] = 1000, 20000, 60000
    cv2.imwrite(str(tmp_path / "rgb.png"), image[:, :, ::-1])  # OpenCV writes BGR
    photo = read_photo(tmp_path / "rgb.png")
    assert photo.channel_index is None and photo.white_level == 65535
    assert photo.values[0, 0].tolist() == [1000, 20000, 60000]


def test_an_8_bit_image_is_refused_unless_its_encoding_is_given(tmp_path):
    path = synthetic.write_tiff(tmp_path / "rgb8.tif", np.full((8, 8, 3), 128.0), np.uint8)
    with pytest.raises(InputError, match="8-bit image, most likely gamma-encoded"):
        read_photo(path)
    decoded = read_photo(path, encoding="srgb")
    # sRGB 128/255 is 21.6 % linear: 55.04 of 255.
    assert decoded.values[0, 0, 0] == pytest.approx(55.04, abs=0.01)
    assert "decoded from sRGB" in (decoded.note or "")
    assert read_photo(path, encoding="linear").values[0, 0, 0] == 128


@pytest.mark.parametrize("layout", ["rgb", "mosaic"])
def test_the_patches_between_the_corners_have_the_drawn_rgb(tmp_path, layout):
    image = synthetic.rgb_image()
    if layout == "rgb":
        photo = read_photo(synthetic.write_tiff(tmp_path / "rgb.tif", image))
    else:
        path = synthetic.write_tiff(tmp_path / "raw.tif", synthetic.mosaic(image))
        photo = read_photo(path, bayer="rggb")
    statistics = sample_patches(photo, synthetic.CORNERS, 4, 6)
    drawn = synthetic.patch_rgb("D65", 40000.0)
    # Noise of 40 DN over hundreds of sites: the means within 10 DN of 40000.
    np.testing.assert_allclose(statistics.mean, drawn, atol=10.0)
    assert np.all(statistics.clipped == 0) and statistics.pixels.min() > 100


def test_exposures_merge_past_clipping_and_above_the_floor(tmp_path):
    image = synthetic.rgb_image(peak=40000.0)
    bright = read_photo(synthetic.write_tiff(tmp_path / "bright.tif", 4 * image))  # white clips
    short = read_photo(synthetic.write_tiff(tmp_path / "short.tif", image))
    statistics = [sample_patches(p, synthetic.CORNERS, 4, 6) for p in (bright, short)]
    assert statistics[0].clipped.max() > 0.9  # the white patch and more
    merged = merge_exposures(statistics, [4.0, 1.0], white_level=65535)
    drawn = synthetic.patch_rgb("D65", 40000.0)
    np.testing.assert_allclose(merged.rgb, drawn, rtol=2e-3, atol=5.0)
    clipped = statistics[0].clipped > 0
    assert np.all(merged.exposures_used[clipped] == 1)
    assert np.all(merged.exposures_used[~clipped & (statistics[1].mean > 0.02 * 65535)] == 2)


def test_colour_checker_detection_finds_the_chart(tmp_path):
    photo = read_photo(synthetic.write_tiff(tmp_path / "rgb.tif", synthetic.rgb_image()))
    corners = detect_colorchecker(photo)
    # Measured: within 12.6 px of the corners of the patches' grid (the detector's quadrilateral
    # lies a little outside), in the same order.
    assert np.abs(corners - synthetic.CORNERS).max() < 16
    found = sample_patches(photo, corners, 4, 6).mean
    np.testing.assert_allclose(found, synthetic.patch_rgb("D65", 40000.0), atol=15.0)


def test_colour_checker_detection_finds_the_chart_in_a_portrait_mosaic(tmp_path):
    """The detector turns portrait images; the corners come back in the photograph's frame (the
    chart turned with it: its first patch at the top right)."""
    turned = np.ascontiguousarray(np.rot90(synthetic.rgb_image(), -1))  # clockwise
    path = synthetic.write_tiff(tmp_path / "portrait.tif", synthetic.mosaic(turned))
    corners = detect_colorchecker(read_photo(path, bayer="rggb"))
    height = synthetic.SHAPE[0]
    expected = np.column_stack([height - 1 - synthetic.CORNERS[:, 1], synthetic.CORNERS[:, 0]])
    assert np.abs(corners - expected).max() < 16  # measured 12.8 px on the RGB image


@pytest.fixture(scope="module")
def two_lights(tmp_path_factory):
    """The Nikon D100 (not among the prior's cameras) under D65 and under A, one photo each."""
    folder = tmp_path_factory.mktemp("two_lights")
    photographs = [
        ChartPhotograph(
            read_photo(synthetic.write_dng(folder / f"{light}.dng", light)),
            light,
            1.0,
            synthetic.CORNERS,
        )
        for light in ("D65", "A")
    ]
    lights = {light: light_spectrum(light) for light in ("D65", "A")}
    return photographs, lights


def test_a_camera_outside_the_prior_is_recovered_from_two_raw_photographs(two_lights):
    """Against the D100's measured sensitivities: measured 4.6 % of the peak (worst channel)
    with the default prior, 5.5 % without; its white balance under both lights within 0.1 %."""
    photographs, lights = two_lights
    truth = MeasuredResponse("isetbio Nikon D100", curves=synthetic.camera_truth())
    chart = named_chart("colorchecker")
    with_prior = truth_errors(characterize_photographs(photographs, chart, lights), truth)
    without = truth_errors(characterize_photographs(photographs, chart, lights, prior=None), truth)
    assert with_prior.curve_pct is not None and without.curve_pct is not None
    assert with_prior.curve_pct.max() < 5.0
    assert without.curve_pct.max() > with_prior.curve_pct.max() + 0.5
    assert with_prior.per_light_pct.max() < 0.3


def test_the_fit_explains_the_patches(two_lights):
    photographs, lights = two_lights
    result = characterize_photographs(photographs, named_chart("colorchecker"), lights)
    assert result.rgb.shape == (2, 24, 3) and result.response.max() == 1.0
    # Noise-free but for 0.1 % noise: residuals of Eq. 9.7 within 3 % of the mean RGB.
    assert np.abs(result.residuals).max() < 0.03


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda p: read_photo(p / "chart.jpg"), "no such file"),
        (lambda p: read_photo(_touch(p / "chart.jpg")), "JPEG is lossy"),
        (lambda p: read_photo(_touch(p / "chart.tif")), "not a readable TIFF"),
        (lambda p: read_photo(_touch(p / "chart.nef")), "not a raw file LibRaw reads"),
        (
            lambda p: read_photo(synthetic.write_tiff(p / "m.tif", np.ones((8, 8)))),
            "expected its Bayer pattern",
        ),
        (
            lambda p: read_photo(_tiff(p / "rgba.tif", np.ones((8, 8, 4), np.uint16))),
            "expected one channel",
        ),
        (
            lambda p: read_photo(_tiff(p / "i32.tif", np.ones((8, 8, 3), np.int32))),
            "int32 pixels",
        ),
        (
            lambda p: sample_patches(
                _photo(p), synthetic.CORNERS + [[0, 0], [0, 0], [0, 500], [0, 0]], 4, 6
            ),
            r"corner 3 \(740, 1040\) lies outside",
        ),
        (
            lambda p: sample_patches(_photo(p), synthetic.CORNERS[[0, 2, 1, 3]], 4, 6),
            "not a convex quadrilateral",
        ),
        (
            lambda p: sample_patches(_photo(p), synthetic.CORNERS, 4, 6, fraction=0.005),
            "R sites; expected at least 4",
        ),
        (lambda p: chart_from_csv(_csv(p, "1,0.5,0.5\n2,0.5,0.5\n"), 2, 2), "2 patches"),
        (lambda p: chart_from_csv(_csv(p, "1,50,60\n2,50,60\n"), 1, 2), "not percent"),
        (lambda p: chart_from_csv(_csv(p, "1,0.5,nan\n2,0.5,0.5\n"), 1, 2), "line 2: NaN"),
        (lambda p: light_spectrum("candle"), "expected a CIE illuminant"),
        (lambda p: light_spectrum(str(_csv(p, "1,1,1\n2,1,1\n"))), "2 spectra; expected one"),
    ],
)
def test_bad_input_is_refused_in_one_line(tmp_path, call, message):
    with pytest.raises(InputError, match=message) as refused:
        call(tmp_path)
    assert "\n" not in str(refused.value)


def _touch(path):
    path.write_bytes(b"not an image")
    return path


def _tiff(path, array):
    tifffile.imwrite(path, array, photometric="rgb" if array.shape[-1] == 3 else None)
    return path


def _csv(folder, rows):
    path = folder / "spectra.csv"
    path.write_text("wavelength_nm,a,b\n" + rows)
    return path


def _photo(folder):
    return read_photo(synthetic.write_tiff(folder / "rgb.tif", synthetic.rgb_image()))
