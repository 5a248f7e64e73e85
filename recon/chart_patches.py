"""Statistics of a chart's patches in raw Bayer frames: the same numbers for real and predicted
frames.

A chart frame is summarized per patch and per Bayer channel by the mean and spatial spread of its
pixels inside the patch (the patch's label mask, eroded so that chromatic aberration and
resampling at the patch's edge stay out), and by the fraction of those pixels at the frame's top
value (clipped). A dark frame is summarized by its mean, its spatial spread, the fraction of
pixels above zero and, from two frames of the same exposure, its temporal spread.

Examples
--------
>>> import numpy as np
>>> labels = np.zeros((8, 8), np.uint8); labels[2:6, 2:6] = 1
>>> channels = np.zeros((8, 8), int)
>>> frame = np.full((8, 8), 200, np.uint8); frame[2, 2] = 255
>>> stats = patch_statistics(frame, patch_masks(labels, 1, erode_px=0), channels, top_dn=255)
>>> float(stats.mean[0, 0]), float(stats.clipped[0, 0])
(203.4375, 0.0625)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from recon.errors import InputError

__all__ = [
    "DarkStatistics",
    "PatchStatistics",
    "dark_statistics",
    "patch_masks",
    "patch_statistics",
]


@dataclass(frozen=True)
class PatchStatistics:
    """Per patch and channel (R, G, B): ``mean`` and ``spread`` (standard deviation) of the pixel
    values, ``clipped`` (fraction at the top value) and ``pixels`` (count), each
    ``(n_patches, 3)``; NaN where a patch has no pixel of a channel."""

    mean: np.ndarray
    spread: np.ndarray
    clipped: np.ndarray
    pixels: np.ndarray


def patch_masks(labels: np.ndarray, count: int, *, erode_px: int) -> np.ndarray:
    """``(count, H, W)`` bool masks of patches ``1..count`` of a label image, eroded by
    ``erode_px`` pixels."""
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise InputError(f"labels: expected a 2-D label image, got shape {labels.shape}")
    masks = np.stack([labels == index for index in range(1, count + 1)])
    if erode_px > 0:
        masks = np.stack([ndimage.binary_erosion(mask, iterations=erode_px) for mask in masks])
    empty = [index + 1 for index, mask in enumerate(masks) if not mask.any()]
    if empty:
        raise InputError(f"labels: patches {empty} have no pixels left after eroding {erode_px} px")
    return masks


def patch_statistics(
    frame: np.ndarray, masks: np.ndarray, channel_index: np.ndarray, *, top_dn: float
) -> PatchStatistics:
    """Statistics of one raw frame ``(H, W)`` over the patch ``masks`` ``(n, H, W)``, per channel
    of ``channel_index`` ``(H, W)`` (0 = R, 1 = G, 2 = B)."""
    frame = np.asarray(frame, dtype=np.float64)
    if frame.shape != masks.shape[1:] or frame.shape != channel_index.shape:
        raise InputError(
            f"frame: expected shape {masks.shape[1:]} like the masks and channels, got "
            f"{frame.shape}"
        )
    shape = (masks.shape[0], 3)
    mean, spread, clipped, pixels = (np.full(shape, np.nan) for _ in range(4))
    for patch, mask in enumerate(masks):
        for channel in range(3):
            values = frame[mask & (channel_index == channel)]
            pixels[patch, channel] = values.size
            if values.size:
                mean[patch, channel] = values.mean()
                spread[patch, channel] = values.std()
                clipped[patch, channel] = np.mean(values >= top_dn)
    return PatchStatistics(mean, spread, clipped, pixels)


@dataclass(frozen=True)
class DarkStatistics:
    """Dark frames of one exposure time: ``mean``, spatial ``spread``, ``above_zero`` (fraction
    of pixels above 0) and ``temporal_spread`` (the spread of the difference of two frames over
    the square root of 2; NaN with one frame)."""

    mean: float
    spread: float
    above_zero: float
    temporal_spread: float


def dark_statistics(frames: np.ndarray) -> DarkStatistics:
    """Statistics of the dark frames ``(n, H, W)`` of one exposure time."""
    frames = np.asarray(frames, dtype=np.float64)
    if frames.ndim != 3 or frames.shape[0] < 1:
        raise InputError(f"frames: expected (n, H, W) dark frames, got {frames.shape}")
    temporal = (
        float(np.std(frames[1] - frames[0]) / np.sqrt(2)) if frames.shape[0] > 1 else float("nan")
    )
    return DarkStatistics(
        mean=float(frames.mean()),
        spread=float(frames.std(axis=(1, 2)).mean()),
        above_zero=float(np.mean(frames > 0)),
        temporal_spread=temporal,
    )
