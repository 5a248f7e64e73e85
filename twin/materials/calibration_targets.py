"""Calibration targets as surfaces in the sample frame: the Zenith white standard (thesis 3.3,
Eq. 3.3), colour charts (the ColorChecker; the Esser test chart of ``recon/data``) and the
printed checkerboard of the dome's geometric calibration (OpenCV's chessboard pattern).

Patches are separate flat parts with their measured reflectance, on a black card, laid out row
by row from the top left; the parts are named ``patch_<index>`` in the chart's order.
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.components.targets import (
    colorchecker_reflectances,
    esser_reflectances,
    zenith_white_reflectance,
)
from twin.materials.geometry import box
from twin.materials.surfaces import SurfacePart

__all__ = [
    "CHART_FILL",
    "ESSER_COLUMNS",
    "chart_field_centres",
    "chart_parts",
    "checkerboard_corners",
    "checkerboard_target",
    "colorchecker_chart",
    "esser_chart",
    "zenith_white_target",
]

ESSER_COLUMNS = 11
"""Fields per row of the Esser chart (:func:`esser_chart`)."""

CHART_FILL = 0.8
"""Side of a chart's coloured square relative to the pitch of its fields."""

_CARD_THICKNESS_M = 0.001
_PRINT_THICKNESS_M = 0.00002


def zenith_white_target(size_m: float = 0.05) -> list[SurfacePart]:
    """The Zenith Ultra-White standard: a square of ``size_m`` with its top at z = 0."""
    reflectance = zenith_white_reflectance(FINE_GRID)
    return [SurfacePart("zenith_white", box((0, 0, -0.002), (size_m, size_m, 0.004)), reflectance)]


def chart_field_centres(count: int, columns: int, size_m: float) -> np.ndarray:
    """``(count, 3)`` centres of a chart's fields (:func:`chart_parts`), reading order, on the
    chart's top (z = 0.1 mm above its card's middle).

    Examples
    --------
    >>> (chart_field_centres(2, 2, 0.02)[:, :2] * 1000).round(6).tolist()
    [[-5.0, 0.0], [5.0, 0.0]]
    """
    rows = math.ceil(count / columns)
    pitch = size_m / columns
    index = np.arange(count)
    return np.column_stack(
        [
            -size_m / 2 + (index % columns + 0.5) * pitch,
            rows * pitch / 2 - (index // columns + 0.5) * pitch,
            np.full(count, 0.0001),
        ]
    )


def chart_parts(
    reflectances: SampledSpectra, columns: int, size_m: float, fill: float = CHART_FILL
) -> list[SurfacePart]:
    """A chart of ``len(reflectances.values)`` patches in ``columns`` columns, ``size_m`` wide,
    each a square of ``fill`` times the pitch."""
    count = reflectances.values.shape[0]
    rows = math.ceil(count / columns)
    pitch = size_m / columns
    black = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.03))
    centres = chart_field_centres(count, columns, size_m)
    parts = [
        SurfacePart(
            "card",
            box((0, 0, -_CARD_THICKNESS_M / 2), (size_m, rows * pitch, _CARD_THICKNESS_M)),
            black,
        )
    ]
    for index, centre in enumerate(centres):
        spectrum = SampledSpectra(reflectances.grid, reflectances.values[index])
        parts.append(
            SurfacePart(
                f"patch_{index:03d}",
                box(tuple(centre), (fill * pitch, fill * pitch, 0.0002)),
                spectrum,
            )
        )
    return parts


def colorchecker_chart(size_m: float = 0.05) -> list[SurfacePart]:
    """The 24-patch ColorChecker (6 x 4), ColorChecker N Ohta spectra from ``colour``."""
    return chart_parts(colorchecker_reflectances(FINE_GRID, out_of_range="clamp"), 6, size_m)


def esser_chart(size_m: float = 0.05) -> list[SurfacePart]:
    """The Esser test chart's 113 measured patches (``esser_reflectances``), 11 columns."""
    return chart_parts(esser_reflectances(FINE_GRID, out_of_range="clamp"), ESSER_COLUMNS, size_m)


def checkerboard_target(
    columns: int = 9, rows: int = 8, square_m: float = 0.005, margin_m: float = 0.003
) -> list[SurfacePart]:
    """A checkerboard of ``columns x rows`` squares of ``square_m`` printed on a white card with a
    ``margin_m`` border, centred, the print's top at z = 0 (target frame). The square at the
    corner of negative x and positive y is black. With an odd and an even side it has no
    symmetry that maps black onto black, so its orientation in an image is unambiguous.
    """
    if columns < 3 or rows < 3 or not square_m > 0 or margin_m < 0:
        raise InputError(
            f"checkerboard: expected at least 3 x 3 squares of positive size, got {columns} x "
            f"{rows} of {square_m} m"
        )
    width, height = columns * square_m, rows * square_m
    card_z = -_PRINT_THICKNESS_M - _CARD_THICKNESS_M / 2
    card = box((0, 0, card_z), (width + 2 * margin_m, height + 2 * margin_m, _CARD_THICKNESS_M))
    squares = [
        box(
            (
                -width / 2 + (column + 0.5) * square_m,
                height / 2 - (row + 0.5) * square_m,
                -_PRINT_THICKNESS_M / 2,
            ),
            (square_m, square_m, _PRINT_THICKNESS_M),
        )
        for row in range(rows)
        for column in range(columns)
        if (row + column) % 2 == 0
    ]
    white = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.85))
    black = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.03))
    return [
        SurfacePart("checker_card", card, white),
        # trimesh types the result as any Geometry (or a list); for meshes it is one Trimesh
        SurfacePart("checker_print", trimesh.util.concatenate(squares), black),  # type: ignore[arg-type]
    ]


def checkerboard_corners(columns: int = 9, rows: int = 8, square_m: float = 0.005) -> np.ndarray:
    """The inner corners ``((rows - 1) * (columns - 1), 3)`` of :func:`checkerboard_target`'s
    board in the target frame, row by row from negative x and positive y (OpenCV's order for a
    pattern of ``(columns - 1, rows - 1)`` corners)."""
    column, row = np.meshgrid(np.arange(1, columns), np.arange(1, rows))
    x = (column.ravel() - columns / 2) * square_m
    y = (rows / 2 - row.ravel()) * square_m
    return np.column_stack([x, y, np.zeros_like(x)])
