"""Pixel coordinates given on the command line: four corners as ``x,y;x,y;x,y;x,y``."""

from __future__ import annotations

import numpy as np

from twin.cli.errors import fail

__all__ = ["parse_corners"]


def parse_corners(text: str, option: str) -> np.ndarray:
    """``x,y;x,y;x,y;x,y`` as ``(4, 2)`` pixels; refuses anything else in one line naming
    ``option``."""
    try:
        points = np.array(
            [[float(value) for value in point.split(",")] for point in text.split(";")]
        )
    except ValueError:
        points = np.empty(0)
    if points.shape != (4, 2) or not np.all(np.isfinite(points)):
        fail(f"{option} {text!r}: expected four points 'x,y;x,y;x,y;x,y' in pixels")
    return points
