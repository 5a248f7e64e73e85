"""Reduced copies of raw frames (twin.sensor.reduced_copy) and GBRG mosaics in the sensor model.

The fast bilinear demosaicing is checked against colour-demosaicing's, the peer it replaces, for
every Bayer tile; the reduction against scikit-image's resize, whose work it restricts to what the
re-mosaiced frame reads, and against frames whose reduced values follow by hand.
"""

from __future__ import annotations

import numpy as np
import pytest
from colour_demosaicing import demosaicing_CFA_Bayer_bilinear
from skimage.transform import resize

from recon.spectra import WavelengthGrid
from twin.rigs.camera_config import load_camera_config
from twin.sensor.model import Sensor, bayer_channel_index, mosaic_channels
from twin.sensor.reduced_copy import bilinear_demosaic, reduce_linear, reduce_raw_frame


@pytest.mark.parametrize("pattern", ["RGGB", "GBRG", "GRBG", "BGGR"])
def test_bilinear_demosaic_equals_colour_demosaicing(pattern):
    raw = np.random.default_rng(1).integers(0, 4096, (30, 34)).astype(np.float64)
    ours = bilinear_demosaic(raw, pattern)
    peer = demosaicing_CFA_Bayer_bilinear(raw, pattern)
    assert np.abs(ours - peer).max() <= 1e-3 * 4096


@pytest.mark.parametrize("pattern", ["RGGB", "GBRG"])
def test_the_reduction_is_scikit_images_resize_bit_for_bit(pattern):
    """Whole, fractional and unit factors: the same bits as resizing the demosaiced frame."""
    rng = np.random.default_rng(4)
    for raw_shape, shape in (((120, 144), (20, 24)), ((61, 75), (13, 11)), ((50, 40), (50, 20))):
        raw = rng.random(raw_shape).astype(np.float32) * 4095
        rgb = bilinear_demosaic(raw, pattern)
        peer = resize(rgb, (*shape, 3), order=1, anti_aliasing=True, preserve_range=True)
        expected = mosaic_channels(peer, bayer_channel_index(*shape, pattern))
        assert np.array_equal(reduce_linear(raw, pattern, shape), expected)


def test_a_grey_frame_reduces_to_its_level_in_the_stored_bits():
    raw = np.full((120, 144), 1000, np.uint16)
    stored = reduce_raw_frame(raw, pattern="GBRG", raw_bit_depth=12, shape=(20, 24), bit_depth=8)
    assert stored.dtype == np.uint8
    assert np.all(stored[2:-2, 2:-2] == round(1000 * 255 / 4095))


def test_the_reduction_keeps_each_channel_apart():
    """A raw frame with red sites at 4000, green at 2000 and blue at 0: every reduced pixel keeps
    its own channel's level (away from the border)."""
    channel = bayer_channel_index(120, 144, "GBRG")
    raw = np.choose(channel, [4000.0, 2000.0, 0.0])
    reduced = reduce_linear(raw, "GBRG", (20, 24))
    expected = np.choose(bayer_channel_index(20, 24, "GBRG"), [4000.0, 2000.0, 0.0])
    assert np.allclose(reduced[2:-2, 2:-2], expected[2:-2, 2:-2], atol=1e-3)


def test_the_flea3_is_a_gbrg_colour_sensor_with_its_filter_band_ratios():
    camera = load_camera_config("flea3_fl3_ge_50s5c")
    sensor = Sensor(camera, roi=(4, 4))
    assert sensor.is_colour and camera.mosaic == "GBRG"
    electrons = np.zeros((4, 4, 3), np.float32)
    electrons[..., 0] = 4000  # red everywhere: only the red sites of GBRG (row 1, column 0) see it
    frame = sensor.capture(electrons, 0.01, np.random.default_rng(0))
    red_sites = bayer_channel_index(4, 4, "GBRG") == 0
    assert frame[red_sites].min() > 1000 and frame[~red_sites].max() < 50
    qe = sensor.quantum_efficiency(WavelengthGrid(np.array([546.0, 640.0, 692.0])))
    # sensor.mat's R/G ratios behind the 550, 650 and 700 nm filters (Llanos 2019)
    assert qe.values[0] / qe.values[1] == pytest.approx([0.0145803, 8.67242, 1.99582], rel=1e-5)


def test_defect_pixels_read_their_offset_at_every_exposure():
    camera = load_camera_config("flea3_fl3_ge_50s5c")
    pattern = camera.fixed_pattern.model_copy(
        update={"defect_pixel_fraction": 1e-3, "defect_offset_dn": 1500.0}
    )
    sensor = Sensor(camera.model_copy(update={"fixed_pattern": pattern}), roi=(200, 200))
    defects = sensor.defect_pixels()
    assert 0.5e-3 < defects.mean() < 2e-3
    for exposure in (0.001, 1.0):
        frame = sensor.dark_frame(exposure, np.random.default_rng(2)).astype(float)
        assert np.abs(frame[defects] - 1500).max() < 25  # read noise 3.3 DN
        assert frame[~defects].mean() < 5
    # without defects the camera's other patterns are the ones it had
    plain = Sensor(camera, roi=(200, 200))
    assert not plain.defect_pixels().any()
    electrons = np.full((200, 200, 3), 1000.0, np.float32)
    same = Sensor(camera.model_copy(update={"fixed_pattern": pattern}), roi=(200, 200))
    first = plain.capture(electrons, 0.01, np.random.default_rng(5)).astype(float)
    second = same.capture(electrons, 0.01, np.random.default_rng(5)).astype(float)
    assert np.array_equal(first[~defects], second[~defects])
