"""Reduced copies of raw Bayer frames, as data sets ship them to save space.

Some real captures keep small copies of their raw frames rather than the frames: the llanos2019
frames were bilinearly demosaiced, resized to 1/6 of their size with anti-aliasing, re-mosaiced
to the camera's Bayer pattern and quantized from the raw range to 8 bits (the author's
``DemoDataPreprocessing.m``, see ``recon/llanos_capture``). The twin predicts such a frame by
simulating the raw frame and reducing it the same way, so that its averaging of neighbouring
pixels, its clipping and its quantization are those of the stored copy.
"""

from __future__ import annotations

import cv2
import numpy as np
from skimage.transform import resize

from recon.errors import InputError
from twin.sensor.model import bayer_channel_index, mosaic_channels

__all__ = ["bilinear_demosaic", "reduce_linear", "reduce_raw_frame"]

_GREEN_KERNEL = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]], np.float32) / 4
_RED_BLUE_KERNEL = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], np.float32) / 4


def bilinear_demosaic(raw: np.ndarray, pattern: str) -> np.ndarray:
    """Bilinear demosaicing of a Bayer frame ``(H, W)`` to ``(H, W, 3)`` float32.

    The interpolation of ``colour_demosaicing.demosaicing_CFA_Bayer_bilinear`` (each channel's
    sites convolved with the bilinear kernel, the border reflected), computed with OpenCV's
    ``filter2D`` in single precision: about ten times faster on a 5 MP frame, which matters when
    every frame of a capture is simulated at full size.
    """
    height, width = raw.shape
    channel = bayer_channel_index(height, width, pattern)
    values = np.asarray(raw, np.float32)
    planes = []
    for index, kernel in enumerate((_RED_BLUE_KERNEL, _GREEN_KERNEL, _RED_BLUE_KERNEL)):
        sites = np.where(channel == index, values, np.float32(0))
        planes.append(cv2.filter2D(sites, -1, kernel, borderType=cv2.BORDER_REFLECT))
    return np.stack(planes, axis=-1)


def reduce_linear(raw: np.ndarray, pattern: str, shape: tuple[int, int]) -> np.ndarray:
    """The reduction of :func:`reduce_raw_frame` before quantization: demosaicing, resizing to
    ``shape`` and re-mosaicing, linear in ``raw`` (float ``shape``)."""
    raw = np.asarray(raw)
    if raw.ndim != 2 or shape[0] > raw.shape[0] or shape[1] > raw.shape[1]:
        raise InputError(f"raw: expected a 2-D frame at least {shape}, got shape {raw.shape}")
    rgb = bilinear_demosaic(raw, pattern)
    small = resize(rgb, (*shape, 3), order=1, anti_aliasing=True, preserve_range=True)
    return mosaic_channels(small, bayer_channel_index(*shape, pattern))


def reduce_raw_frame(
    raw: np.ndarray,
    *,
    pattern: str,
    raw_bit_depth: int,
    shape: tuple[int, int],
    bit_depth: int,
) -> np.ndarray:
    """A raw Bayer frame ``(H, W)`` reduced to ``shape`` and ``bit_depth`` bits.

    Parameters
    ----------
    raw
        The raw frame, digital numbers of ``raw_bit_depth`` bits.
    pattern
        Its Bayer tile, e.g. ``"GBRG"``; the reduced frame keeps it.
    raw_bit_depth, bit_depth
        Bits of the raw and of the reduced frame: the raw range maps onto the reduced one.
    shape
        ``(height, width)`` of the reduced frame.

    Returns
    -------
    numpy.ndarray
        ``shape`` unsigned integers (uint8 up to 8 bits, uint16 above).

    Examples
    --------
    A flat raw frame at mid-range stays flat away from the border (where bilinear demosaicing
    mirrors the mosaic):

    >>> flat = np.full((60, 60), 2048, np.uint16)
    >>> reduced = reduce_raw_frame(
    ...     flat, pattern="GBRG", raw_bit_depth=12, shape=(10, 10), bit_depth=8
    ... )
    >>> reduced[3:7, 3:7].tolist() == [[128] * 4] * 4
    True
    """
    mosaic = reduce_linear(raw, pattern, shape)
    top = 2**bit_depth - 1
    scaled = np.rint(mosaic * (top / (2**raw_bit_depth - 1)))
    return np.clip(scaled, 0, top).astype(np.uint8 if bit_depth <= 8 else np.uint16)
