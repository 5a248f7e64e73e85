"""Input checks and constants shared by the spectral recovery methods of :mod:`recon.baselines`.

Each ``check_*`` function returns its argument as a validated ``float64`` array (or number,
or index array) following the conventions of :mod:`recon.baselines`, and raises
:class:`recon.errors.InputError` naming the argument otherwise.
"""

from __future__ import annotations

import numpy as np

from recon.errors import InputError

__all__ = [
    "CHUNK_ELEMENTS",
    "check_array",
    "check_count",
    "check_image",
    "check_known_pixels",
    "check_known_rgb",
    "check_positive",
    "check_reflectance_rgb",
    "check_response",
    "check_spectra",
    "check_target_pixels",
]

CHUNK_ELEMENTS = 1 << 22
"""Pixels x (known points or atoms) evaluated at once, to bound the memory of the kernels."""


def check_array(name: str, value: object) -> np.ndarray:
    """``value`` as a ``float64`` array of finite numbers."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"{name}: expected a numeric array, got {type(value)}") from error
    bad = int(np.size(array) - np.count_nonzero(np.isfinite(array)))
    if bad:
        raise InputError(f"{name}: expected finite values, found {bad} NaN or infinite entries")
    return array


def check_image(name: str, value: object, channels: int | None = None) -> np.ndarray:
    """A ``(..., C)`` image with at least one pixel."""
    array = check_array(name, value)
    if array.ndim < 1 or array.shape[-1] < 1 or array.size == 0:
        raise InputError(
            f"{name}: expected an array of shape (..., C) with C >= 1 channels and at least one "
            f"pixel, got shape {array.shape}"
        )
    if channels is not None and array.shape[-1] != channels:
        raise InputError(
            f"{name}: expected {channels} channels on the last axis, got shape {array.shape}"
        )
    return array


def check_response(value: object, bands: int | None, channels: int) -> np.ndarray:
    """A ``(K, C)`` response whose C matches the RGB data and K the spectra (if known)."""
    response = check_array("response", value)
    if response.ndim != 2 or response.shape[1] != channels:
        raise InputError(
            f"response: expected shape (K, {channels}) so that rgb = spectra @ response "
            f"(thesis Eq. 6.2), got shape {response.shape}"
        )
    if bands is not None and response.shape[0] != bands:
        raise InputError(
            f"response: has {response.shape[0]} bands but the spectra have K = {bands}; "
            f"expected shape ({bands}, {channels})"
        )
    if response.shape[0] < 1 or not np.any(response):
        raise InputError("response: expected a non-zero (K, C) matrix with K >= 1")
    return response


def check_spectra(name: str, value: object, bands: int | None = None) -> np.ndarray:
    """``(m, K)`` known or training spectra, at least one."""
    spectra = check_array(name, value)
    if spectra.ndim != 2:
        raise InputError(
            f"{name}: expected a 2-D array of shape (m, K), one spectrum per row, got shape "
            f"{spectra.shape}"
        )
    if spectra.shape[0] < 1:
        raise InputError(
            f"{name}: no known spectra; expected shape (m, K) with m >= 1, got {spectra.shape}"
        )
    if spectra.shape[1] < 1:
        raise InputError(f"{name}: expected K >= 1 bands, got shape {spectra.shape}")
    if bands is not None and spectra.shape[1] != bands:
        raise InputError(
            f"{name}: has K = {spectra.shape[1]} bands, expected {bands} (the response's K)"
        )
    return spectra


def _flat_indices(
    value: object, n_pixels: int, image_shape: tuple[int, ...], name: str
) -> np.ndarray:
    """1-D integer flat row-major indices into the image's leading dimensions."""
    indices = np.asarray(value)
    if indices.dtype == bool:
        raise InputError(
            f"{name}: expected flat integer indices into rgb.shape[:-1], got a boolean "
            f"mask; pass np.flatnonzero(mask) (rows of known_spectra in row-major mask order)"
        )
    if indices.ndim != 1 or not (np.issubdtype(indices.dtype, np.integer) or indices.size == 0):
        raise InputError(
            f"{name}: expected a 1-D array of integer flat indices into rgb.shape[:-1] "
            f"= {image_shape}, got dtype {indices.dtype} and shape {indices.shape}"
        )
    indices = indices.astype(np.int64)
    if indices.size and (indices.min() < 0 or indices.max() >= n_pixels):
        raise InputError(
            f"{name}: expected flat indices in [0, {n_pixels}) for an image of shape "
            f"{image_shape}, got range [{indices.min()}, {indices.max()}]"
        )
    return indices


def check_known_pixels(
    value: object, n_pixels: int, count: int, image_shape: tuple[int, ...]
) -> np.ndarray:
    """Distinct flat row-major indices into the image's leading dimensions."""
    indices = _flat_indices(value, n_pixels, image_shape, "known_pixels")
    if indices.size != count:
        raise InputError(
            f"known_pixels: expected one index per known spectrum ({count}), got {indices.size}"
        )
    if np.unique(indices).size != indices.size:
        raise InputError("known_pixels: expected distinct pixel indices, found repeats")
    return indices


def check_target_pixels(value: object, n_pixels: int, image_shape: tuple[int, ...]) -> np.ndarray:
    """Flat row-major indices of the pixels to estimate (``at_pixels``)."""
    return _flat_indices(value, n_pixels, image_shape, "at_pixels")


def check_known_rgb(
    pixels: np.ndarray,
    known_spectra: np.ndarray,
    known_pixels: object,
    known_rgb: object,
    image_shape: tuple[int, ...],
) -> np.ndarray:
    """RGB of the known spectra: from the image at ``known_pixels`` or given as ``known_rgb``."""
    if (known_pixels is None) == (known_rgb is None):
        raise InputError(
            f"known_pixels / known_rgb: expected exactly one of them (the pixels of the known "
            f"spectra in rgb, or their RGB values), got "
            f"{'both' if known_pixels is not None else 'neither'}"
        )
    if known_pixels is not None:
        index = check_known_pixels(known_pixels, len(pixels), len(known_spectra), image_shape)
        return pixels[index]
    values = check_image("known_rgb", known_rgb, pixels.shape[-1])
    if values.shape != (len(known_spectra), pixels.shape[-1]):
        raise InputError(
            f"known_rgb: expected shape ({len(known_spectra)}, {pixels.shape[-1]}), one RGB "
            f"per known spectrum, got {values.shape}"
        )
    return values


def check_positive(name: str, value: float, allow_zero: bool = False) -> float:
    """A finite number > 0 (>= 0 with ``allow_zero``)."""
    value = float(value)
    if not np.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{name}: expected a finite number {bound}, got {value}")
    return value


def check_count(name: str, value: object, low: int, high: int | None = None) -> int:
    """An integer (not a bool) in ``[low, high]``; ``high=None`` for no upper bound."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InputError(f"{name}: expected an integer, got {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        upper = f" and <= {high}" if high is not None else ""
        raise InputError(f"{name}: expected an integer >= {low}{upper}, got {value}")
    return value


def check_reflectance_rgb(rgb: object) -> np.ndarray:
    """A ``(..., 3)`` linear sRGB reflectance image with values in [0, 1]."""
    array = check_image("rgb", rgb, 3)
    if array.min() < 0 or array.max() > 1:
        raise InputError(
            f"rgb: expected linear sRGB reflectance values in [0, 1], got range "
            f"[{array.min():g}, {array.max():g}]; map camera RGB to linear sRGB and clip first"
        )
    return array
