"""Pieces of the dome's camera processing: Bayer quads, texel means, curve linearity."""

from __future__ import annotations

import numpy as np
import pytest
from colour_demosaicing import masks_CFA_Bayer

from recon.calibration.dome import curve_linearity, texel_mean
from recon.errors import InputError
from recon.radiometric.demosaic import bin_quads


@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_bin_quads_matches_colour_demosaicings_masks(pattern, rng):
    """Each quad's channels, located with colour-demosaicing's CFA masks as the peer."""
    mosaic = rng.random((6, 8))
    rgb = bin_quads(mosaic, pattern=pattern)
    masks = masks_CFA_Bayer(mosaic.shape, pattern)
    for channel, mask in enumerate(masks):
        values = np.where(mask, mosaic, 0).reshape(3, 2, 4, 2).sum((1, 3))
        counts = mask.reshape(3, 2, 4, 2).sum((1, 3))
        np.testing.assert_allclose(rgb[..., channel], values / counts)


def test_bin_quads_needs_even_sides():
    with pytest.raises(InputError, match="even sides"):
        bin_quads(np.zeros((5, 4)))


def test_texel_mean_averages_blocks_and_keeps_channels():
    image = np.arange(4 * 6 * 2, dtype=float).reshape(4, 6, 2)
    means = texel_mean(image, 2)
    assert means.shape == (2, 3, 2)
    assert means[0, 0, 1] == pytest.approx(np.mean(image[:2, :2, 1]))
    with pytest.raises(InputError, match="divisor"):
        texel_mean(image, 4)


def test_curve_linearity_of_a_line_and_a_knee():
    levels = np.arange(100, dtype=float)
    line = np.where(levels >= 10, (levels - 10) * 0.5, np.nan)
    assert curve_linearity(line, 10) == pytest.approx(0.0, abs=1e-12)
    knee = np.where(levels >= 10, (levels - 10) / (1 + 0.002 * (levels - 10)), np.nan)
    assert curve_linearity(knee, 10) > 0.02


@pytest.mark.parametrize("kept", [0, 100, None], ids=["empty", "truncated", "no summary"])
def test_a_damaged_calibration_file_is_refused_by_name(tmp_path, kept):
    """An empty or truncated ``.npz`` (a damaged zip) and one without the calibration's arrays:
    :class:`InputError` naming the file, not ``BadZipFile`` or ``EOFError``."""
    from recon.calibration.dome_capture import DomeCalibration

    path = tmp_path / "dome_cal.npz"
    np.savez_compressed(path, other=np.zeros(3))
    if kept is not None:
        path.write_bytes(path.read_bytes()[:kept])
    with pytest.raises(InputError, match="dome_cal.npz: not a dome calibration file"):
        DomeCalibration.load(path)
