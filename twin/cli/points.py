"""Pixel coordinates given on the command line: four corners as ``x,y;x,y;x,y;x,y``, a circle as
``x,y,radius``."""

from __future__ import annotations

import numpy as np

from twin.cli.errors import fail

__all__ = ["parse_circle", "parse_corners"]


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


def parse_circle(text: str, option: str) -> tuple[float, float, float]:
    """``x,y,radius`` as three floats; refuses anything else in one line naming ``option``."""
    try:
        values = [float(value) for value in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not np.all(np.isfinite(values)):
        fail(f"{option} {text!r}: expected 'x,y,radius' in pixels")
    return values[0], values[1], values[2]
