"""Calibration targets as surfaces in the sample frame: the Zenith white standard (thesis 3.3,
Eq. 3.3) and colour charts (the ColorChecker; the Esser test chart of ``recon/data``).

Patches are separate flat parts with their measured reflectance, on a black card, laid out row
by row from the top left; the parts are named ``patch_<index>`` in the chart's order.
"""

from __future__ import annotations

import math

import numpy as np

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.components.targets import (
    colorchecker_reflectances,
    esser_reflectances,
    zenith_white_reflectance,
)
from twin.materials.geometry import box
from twin.materials.surfaces import SurfacePart

__all__ = ["chart_parts", "colorchecker_chart", "esser_chart", "zenith_white_target"]

_CARD_THICKNESS_M = 0.001


def zenith_white_target(size_m: float = 0.05) -> list[SurfacePart]:
    """The Zenith Ultra-White standard: a square of ``size_m`` with its top at z = 0."""
    reflectance = zenith_white_reflectance(FINE_GRID)
    return [SurfacePart("zenith_white", box((0, 0, -0.002), (size_m, size_m, 0.004)), reflectance)]


def chart_parts(
    reflectances: SampledSpectra, columns: int, size_m: float, fill: float = 0.8
) -> list[SurfacePart]:
    """A chart of ``len(reflectances.values)`` patches in ``columns`` columns, ``size_m`` wide."""
    count = reflectances.values.shape[0]
    rows = math.ceil(count / columns)
    pitch = size_m / columns
    black = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.03))
    parts = [
        SurfacePart(
            "card",
            box((0, 0, -_CARD_THICKNESS_M / 2), (size_m, rows * pitch, _CARD_THICKNESS_M)),
            black,
        )
    ]
    for index in range(count):
        row, column = divmod(index, columns)
        centre = (
            -size_m / 2 + (column + 0.5) * pitch,
            rows * pitch / 2 - (row + 0.5) * pitch,
            0.0001,
        )
        spectrum = SampledSpectra(reflectances.grid, reflectances.values[index])
        parts.append(
            SurfacePart(
                f"patch_{index:03d}", box(centre, (fill * pitch, fill * pitch, 0.0002)), spectrum
            )
        )
    return parts


def colorchecker_chart(size_m: float = 0.05) -> list[SurfacePart]:
    """The 24-patch ColorChecker (6 x 4), ColorChecker N Ohta spectra from ``colour``."""
    return chart_parts(colorchecker_reflectances(FINE_GRID, out_of_range="clamp"), 6, size_m)


def esser_chart(size_m: float = 0.05) -> list[SurfacePart]:
    """The Esser test chart's 113 measured patches (``esser_reflectances``), 11 columns."""
    return chart_parts(esser_reflectances(FINE_GRID, out_of_range="clamp"), 11, size_m)
