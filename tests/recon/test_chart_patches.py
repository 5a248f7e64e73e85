"""Patch and dark-frame statistics of chart frames (recon.chart_patches): against values computed
by hand on small frames, and the temporal spread against the noise that made two frames."""

from __future__ import annotations

import numpy as np
import pytest

from recon.chart_patches import dark_statistics, patch_masks, patch_statistics
from recon.errors import InputError


def test_patch_statistics_per_channel_with_clipping():
    labels = np.zeros((10, 12), np.uint8)
    labels[1:9, 1:5] = 1
    labels[1:9, 6:11] = 2
    channels = np.tile(np.array([[1, 2], [0, 1]]), (5, 6))  # GBRG
    frame = np.where(channels == 0, 100.0, np.where(channels == 1, 50.0, 255.0))
    frame[2, 2] = 52.0  # a green pixel of patch 1
    stats = patch_statistics(frame, patch_masks(labels, 2, erode_px=0), channels, top_dn=255)
    green = frame[1:9, 1:5][channels[1:9, 1:5] == 1]
    assert stats.mean[0, 1] == pytest.approx(green.mean())
    assert stats.spread[0, 1] == pytest.approx(green.std())
    assert stats.mean[:, 0] == pytest.approx([100, 100])
    assert stats.clipped[:, 2] == pytest.approx([1, 1])
    assert stats.clipped[:, 0] == pytest.approx([0, 0])
    assert stats.pixels.sum() == (labels > 0).sum()


def test_masks_are_eroded_and_empty_patches_refused():
    labels = np.zeros((12, 12), np.uint8)
    labels[2:10, 2:10] = 1
    labels[0, 0] = 2
    with pytest.raises(InputError, match=r"patches \[2\] have no pixels"):
        patch_masks(labels, 2, erode_px=1)
    masks = patch_masks(labels[:, :], 1, erode_px=2)
    assert masks[0].sum() == 4 * 4


def test_dark_temporal_spread_is_the_noise_of_the_pair():
    rng = np.random.default_rng(3)
    fixed = rng.integers(0, 3, (200, 200)).astype(float)
    frames = np.stack([fixed + rng.normal(0, 0.7, fixed.shape) for _ in range(2)])
    stats = dark_statistics(frames)
    assert stats.temporal_spread == pytest.approx(0.7, rel=0.02)
    assert stats.spread == pytest.approx(np.sqrt(fixed.var() + 0.49), rel=0.02)
    assert np.isnan(dark_statistics(frames[:1]).temporal_spread)


def test_a_frame_of_another_shape_is_refused():
    labels = np.ones((4, 4), np.uint8)
    with pytest.raises(InputError, match="expected shape"):
        patch_statistics(
            np.zeros((4, 5)), patch_masks(labels, 1, erode_px=0), np.zeros((4, 4), int), top_dn=255
        )
