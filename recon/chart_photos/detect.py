"""A ColorChecker Classic found in a photograph by colour-checker-detection.

The detector (``colour_checker_detection.detect_colour_checkers_segmentation``, the colour-science
project's) segments the chart's swatches in a display-referred RGB image and returns the
quadrilateral around them, turned so that its first patch is the dark skin one. It runs on a
preview of the photograph: each 2 x 2 block of a Bayer mosaic averaged per colour (each 6 x 6
block of another colour filter array), scaled to its bright end and sRGB-encoded. Where it finds
no chart, the corners must be given.

References
----------
- Mansencal, T. et al. colour-checker-detection (BSD-3-Clause),
  https://github.com/colour-science/colour-checker-detection
"""

from __future__ import annotations

import warnings

import colour
import numpy as np

from recon.chart_photos.images import LinearPhoto
from recon.errors import InputError

__all__ = ["detect_colorchecker", "preview"]


def preview(photo: LinearPhoto) -> tuple[np.ndarray, int]:
    """``(image, block)``: an sRGB-encoded RGB preview ``(h, w, 3)`` in [0, 1] of ``photo``
    and the side of the blocks of sites it averages (1 for an RGB photograph)."""
    if photo.channel_index is None:
        block, rgb = 1, photo.values
    else:
        block = 2 if _blocks_hold_every_colour(photo.channel_index, 2) else 6
        height, width = (side // block * block for side in photo.shape)
        channels = []
        for channel in range(3):
            sites = (photo.channel_index[:height, :width] == channel).astype(np.float64)
            total = (photo.values[:height, :width] * sites).reshape(
                height // block, block, width // block, block
            )
            count = sites.reshape(height // block, block, width // block, block).sum(axis=(1, 3))
            channels.append(total.sum(axis=(1, 3)) / np.maximum(count, 1))
        rgb = np.stack(channels, axis=-1)
    bright = float(np.percentile(rgb, 99.5))
    linear = np.clip(rgb / bright if bright > 0 else rgb, 0.0, 1.0)
    return np.asarray(colour.models.eotf_inverse_sRGB(linear), np.float64), block


def _blocks_hold_every_colour(channel_index: np.ndarray, block: int) -> bool:
    tile = channel_index[:block, :block]
    return bool(set(np.unique(tile).tolist()) == {0, 1, 2})


def detect_colorchecker(photo: LinearPhoto) -> np.ndarray:
    """The four outer corners ``(4, 2)`` (x, y in pixels) of a ColorChecker Classic's patches
    in ``photo``, the first at the dark skin patch, then along its row (the order of
    ``recon.chart_photos.patches.sample_patches``).

    Raises
    ------
    InputError
        Where the detector finds no chart (the corners must then be given).
    """
    from colour_checker_detection import detect_colour_checkers_segmentation
    from colour_checker_detection.detection.common import SETTINGS_DETECTION_COLORCHECKER_CLASSIC

    image, block = preview(photo)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = detect_colour_checkers_segmentation(image, additional_data=True)
    if not found:
        raise InputError(
            f"photo {photo.source}: colour-checker-detection found no ColorChecker; expected "
            "the chart's corners"
        )
    # The detector turns a portrait image 90 degrees clockwise, resizes it to its working width
    # and returns the quadrilateral that maps to the rectangle (top right, bottom right, bottom
    # left, top left) of the chart.
    height, width = image.shape[:2]
    scale = max(height, width) / SETTINGS_DETECTION_COLORCHECKER_CLASSIC["working_width"]
    quadrilateral = np.asarray(found[0].quadrilateral, np.float64).reshape(4, 2) * scale
    if width < height:
        quadrilateral = np.column_stack([quadrilateral[:, 1], height - 1 - quadrilateral[:, 0]])
    corners = quadrilateral[[3, 0, 1, 2]]
    return (corners + 0.5) * block - 0.5
