"""Reduced copies of raw Bayer frames, as data sets ship them to save space.

Some real captures keep small copies of their raw frames rather than the frames: the llanos2019
frames were bilinearly demosaiced, resized to 1/6 of their size with anti-aliasing, re-mosaiced
to the camera's Bayer pattern and quantized from the raw range to 8 bits (the author's
``DemoDataPreprocessing.m``, see ``recon/llanos_capture``). The twin predicts such a frame by
simulating the raw frame and reducing it the same way, so that its averaging of neighbouring
pixels, its clipping and its quantization are those of the stored copy.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator

import cv2
import numpy as np
from scipy import ndimage

from recon.errors import InputError
from twin.sensor.model import bayer_channel_index

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
    return np.stack(list(_demosaiced_planes(raw, pattern)), axis=-1)


def _demosaiced_planes(raw: np.ndarray, pattern: str) -> Iterator[np.ndarray]:
    """The R, G and B planes ``(H, W)`` float32 of :func:`bilinear_demosaic`, one by one."""
    height, width = raw.shape
    channel = bayer_channel_index(height, width, pattern)
    values = np.asarray(raw, np.float32)
    for index, kernel in enumerate((_RED_BLUE_KERNEL, _GREEN_KERNEL, _RED_BLUE_KERNEL)):
        sites = np.where(channel == index, values, np.float32(0))
        yield cv2.filter2D(sites, -1, kernel, borderType=cv2.BORDER_REFLECT)


def reduce_linear(raw: np.ndarray, pattern: str, shape: tuple[int, int]) -> np.ndarray:
    """The reduction of :func:`reduce_raw_frame` before quantization: demosaicing, resizing to
    ``shape`` and re-mosaicing, linear in ``raw`` (float ``shape``).

    The resize is scikit-image's ``resize(..., order=1, anti_aliasing=True,
    preserve_range=True)``: a Gaussian blur of sigma ``(factor - 1) / 2``, down the columns,
    then along the rows, then ``scipy.ndimage.zoom`` and a clip to the demosaiced range. Here the
    same calls run on what the re-mosaiced frame reads: each plane blurred down its columns on a
    transposed copy (contiguous lines), then along the rows only on the rows its own reduced
    pixels interpolate. The same operations on the same values, so the same bits for a finite
    frame, at about 60 % of the CPU time on a 5 MP frame.
    """
    raw = np.asarray(raw)
    if raw.ndim != 2 or shape[0] > raw.shape[0] or shape[1] > raw.shape[1]:
        raise InputError(f"raw: expected a 2-D frame at least {shape}, got shape {raw.shape}")
    factors = np.divide(raw.shape, shape)
    down_columns, along_rows = np.maximum(0, (factors - 1) / 2)
    reduced_channel = bayer_channel_index(*shape, pattern)
    interpolated = _interpolated_rows(raw.shape[0], shape[0])
    reduced = np.empty(shape, np.float32)
    low, high = np.inf, -np.inf
    blurred_plane = np.zeros(raw.shape, np.float32)  # zero but on the rows a plane blurs
    for index, plane in enumerate(_demosaiced_planes(raw, pattern)):
        low, high = min(low, np.nanmin(plane)), max(high, np.nanmax(plane))
        mine = reduced_channel == index
        rows = np.flatnonzero(interpolated[mine.any(axis=1)].any(axis=0))
        if down_columns > 1e-15:  # as scipy.ndimage.gaussian_filter skips an axis
            columns = cv2.transpose(plane)
            blurred = ndimage.gaussian_filter1d(columns, down_columns, axis=1, mode="mirror")
            selected = np.ascontiguousarray(blurred[:, rows].T)
        else:
            selected = plane[rows]
        if along_rows > 1e-15:
            selected = ndimage.gaussian_filter1d(selected, along_rows, axis=1, mode="mirror")
        blurred_plane[rows] = selected
        small = ndimage.zoom(blurred_plane, 1 / factors, order=1, mode="mirror", grid_mode=True)
        blurred_plane[rows] = 0
        reduced[mine] = small[mine]
    return np.clip(reduced, low, high)


@functools.lru_cache(maxsize=8)
def _interpolated_rows(size: int, reduced: int) -> np.ndarray:
    """``(reduced, size)`` bool: the rows of a ``size``-row image each row of its ``reduced``-row
    zoom (``scipy.ndimage.zoom``, order 1, grid mode, mirrored, as ``resize`` calls it) weighs by
    more than zero, read off the zoom of the identity."""
    zoom = (1 / (size / reduced), 1)
    return ndimage.zoom(np.eye(size), zoom, order=1, mode="mirror", grid_mode=True) > 0


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
