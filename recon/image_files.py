"""Pixels of PNG and TIFF image files as stored, and the encodings an 8-bit image may carry.

OpenCV reads PNGs (it keeps 16 bits; its BGR order is turned to RGB), tifffile reads TIFFs (the
first page; a planar configuration, channels first, is turned to channels last). Neither scales
nor decodes the values: what they mean is for the caller to say (``ENCODINGS``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np

from recon.errors import InputError

__all__ = ["ENCODINGS", "Encoding", "read_png_or_tiff"]

Encoding = Literal["linear", "srgb"]
ENCODINGS: tuple[Encoding, ...] = ("linear", "srgb")


def read_png_or_tiff(path: Path, what: str) -> np.ndarray:
    """The pixels of a PNG or TIFF file as stored, channels last in RGB order.

    Parameters
    ----------
    path
        A ``.png`` file (read by OpenCV) or a TIFF (read by tifffile).
    what
        What the file is to the caller (``"photo"``, ``"image"``), the first word of errors.

    Returns
    -------
    numpy.ndarray
        ``(H, W)`` or ``(H, W, C)`` in the file's own dtype.

    Raises
    ------
    InputError
        Where the file cannot be read as the image its suffix names.
    """
    if path.suffix.lower() == ".png":
        import cv2

        image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise InputError(f"{what} {path}: not a readable PNG image")
        return image[:, :, 2::-1] if image.ndim == 3 and image.shape[2] >= 3 else image
    import tifffile

    try:
        image = np.asarray(tifffile.imread(path, key=0))
    except (tifffile.TiffFileError, ValueError, OSError) as error:
        raise InputError(f"{what} {path}: not a readable TIFF image ({error})") from None
    if image.ndim == 3 and image.shape[0] in (3, 4) and image.shape[2] not in (3, 4):
        image = np.moveaxis(image, 0, -1)  # planar configuration: channels first
    return image
