"""Where a large image is cross-validated: a central window with enough spots.

The cross-validation of :func:`recon.spectralize.choose_appearance` solves the image once per
fold and appearance space (six solves with three folds and two spaces), so on a large image it
costs several times the final solve. It needs the image's structure and the density of its
spots, not every pixel: a central window of about :data:`CROSS_VALIDATION_PIXELS` pixels, of the
image's shape and at its full resolution, keeps both (unlike a downscaled image, which blurs
materials together and shrinks the spots; BENCHMARKS.md, "Spectralizing a user's image"). The
window grows until it holds :data:`MIN_WINDOW_SPOTS` spots. Only its spots are held out, so
only they get a held-out error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from recon.errors import InputError

__all__ = ["CROSS_VALIDATION_PIXELS", "MIN_WINDOW_SPOTS", "Window", "cross_validation_window"]

CROSS_VALIDATION_PIXELS = 100_000
"""Pixels of the window that a larger image is cross-validated in (BENCHMARKS.md,
"Spectralizing a user's image"): on the twelve real-reflectance mosaics and blends at
1000 x 1000 px (spots at 1 %), windows of 100 000 px chose the space and prior the whole image
chose on all twelve, as windows of 90 000 px did at 600 px; a window of 250 000 px took 2.2
times as long to cross-validate at a megapixel (12.0 against 5.5 s)."""
MIN_WINDOW_SPOTS = 500
"""Fewest spots (4-connected groups of known pixels) in the window. On the twelve real-reflectance
mosaics and blends at 600 px (BENCHMARKS.md, "Spectralizing a user's image") windows of 900
spots chose the space and prior the whole image chose on all twelve; windows of 142 spots (of
250) on eleven, the twelfth 31 % worse than the whole image's choice."""
_GROWTH = 1.25  # the window's sides grow by this factor until it holds enough spots


@dataclass(frozen=True)
class Window:
    """``height`` x ``width`` pixels from ``row``, ``col`` (the top left) of an image of
    ``image_shape`` ``(H, W)``."""

    row: int
    col: int
    height: int
    width: int
    image_shape: tuple[int, int]

    @property
    def whole(self) -> bool:
        """Whether the window is the whole image."""
        return (self.height, self.width) == self.image_shape

    @property
    def slices(self) -> tuple[slice, slice]:
        """Its rows and columns, to index an ``(H, W, ...)`` array."""
        return slice(self.row, self.row + self.height), slice(self.col, self.col + self.width)

    def inside(self, pixels: np.ndarray) -> np.ndarray:
        """``(m,)`` bool: which of the image's flat pixel indices lie in the window."""
        rows, cols = np.divmod(np.asarray(pixels), self.image_shape[1])
        return np.asarray(
            (rows >= self.row)
            & (rows < self.row + self.height)
            & (cols >= self.col)
            & (cols < self.col + self.width)
        )

    def local(self, pixels: np.ndarray) -> np.ndarray:
        """The window's flat indices of image pixels that lie in it."""
        rows, cols = np.divmod(np.asarray(pixels), self.image_shape[1])
        return np.asarray((rows - self.row) * self.width + cols - self.col)

    def describe(self) -> str:
        """E.g. ``'the central 500 x 500 px'`` or ``'the whole image'``."""
        if self.whole:
            return "the whole image"
        return f"the central {self.width} x {self.height} px"


def _centred(shape: tuple[int, int], height: int, width: int) -> Window:
    height, width = min(height, shape[0]), min(width, shape[1])
    return Window((shape[0] - height) // 2, (shape[1] - width) // 2, height, width, shape)


def _spot_count(mask: np.ndarray) -> int:
    return int(ndimage.label(mask)[1])


def cross_validation_window(
    image_shape: tuple[int, int],
    known_pixels: np.ndarray,
    pixels: int | None = CROSS_VALIDATION_PIXELS,
) -> Window:
    """The window to cross-validate in (module description).

    Parameters
    ----------
    image_shape
        ``(H, W)`` of the image.
    known_pixels
        Flat indices of the known pixels (the spots).
    pixels
        Pixels of the window; ``None`` (or at least the image's): the whole image.

    Returns
    -------
    Window
        Centred, of the image's aspect ratio and about ``pixels`` pixels, grown until it holds
        :data:`MIN_WINDOW_SPOTS` spots (at most to the whole image).

    Examples
    --------
    >>> import numpy as np
    >>> known = np.ravel_multi_index(np.mgrid[5:1000:10, 5:800:10].reshape(2, -1), (1000, 800))
    >>> cross_validation_window((1000, 800), known).describe()
    'the central 283 x 354 px'
    >>> cross_validation_window((1000, 800), known, None).whole
    True
    """
    height, width = image_shape
    if pixels is not None and pixels < 1:
        raise InputError(f"cross-validation pixels: expected a positive count, got {pixels}")
    if pixels is None or pixels >= height * width:
        return _centred(image_shape, height, width)
    mask = np.zeros(height * width, dtype=bool)
    mask[np.asarray(known_pixels)] = True
    mask = mask.reshape(image_shape)
    scale = np.sqrt(pixels / (height * width))
    while True:
        window = _centred(image_shape, int(round(height * scale)), int(round(width * scale)))
        if window.whole or _spot_count(mask[window.slices]) >= MIN_WINDOW_SPOTS:
            return window
        scale *= _GROWTH
