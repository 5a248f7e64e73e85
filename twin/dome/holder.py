"""What lies on the dome's sample holder for each kind of frame of a capture plan.

The material for ``sample`` and ``alignment`` frames; for calibration frames a target on the
holder (thesis 10.3): the Zenith white standard (``white``), the colour checker (``oecf``, the
response series), or the printed checkerboard of the geometric calibration (``geometric``),
flat or tilted on a wedge by the step's ``tilt_deg`` so that the cameras see it in several
orientations (Zhang's calibration needs more than one plane orientation per camera; the stage
turns the wedge with it). Dark frames see nothing.

Everything is in the sample frame of :mod:`twin.materials.sample_holder` (z the plate normal,
the plate's top at z = 0); the stage turns it all about z.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from hwbridge.schema import CheckerboardTarget, DomeChart, DomeHolder, Spectrum
from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.components.targets import colorchecker_reflectances, esser_reflectances
from twin.materials import Material
from twin.materials.calibration_targets import (
    CHART_FILL,
    ESSER_COLUMNS,
    chart_field_centres,
    checkerboard_corners,
    checkerboard_target,
    colorchecker_chart,
    esser_chart,
    zenith_white_target,
)
from twin.materials.sample_holder import (
    PAPER_INNER_HALF_M,
    PRINT_INNER_HALF_M,
    PRINT_OUTER_HALF_M,
    holder_parts,
    registration_corners,
)
from twin.materials.surfaces import SurfacePart, transformed

__all__ = [
    "CHART_SIZE_M",
    "CHECKERBOARD",
    "chart_geometry",
    "holder_content",
    "holder_geometry",
    "holder_scene_parts",
    "target_geometry",
    "wedge_pose",
]

CHECKERBOARD: dict[str, Any] = {"columns": 9, "rows": 8, "square_m": 0.005, "margin_m": 0.003}
"""The geometric calibration target: 9 x 8 squares of 5 mm (8 x 7 inner corners) on a white
card with a 3 mm border, 51 x 46 mm: it covers the holder's opening and stays inside its frame."""

CHART_SIZE_M = 2 * PAPER_INNER_HALF_M - 0.001
"""Width of the colour checker of the response series: it fills the holder's opening."""


_ON_PLATE_M = 0.0001  # targets in the opening lie this much above the plate, below the paper
_CLEARANCE_M = 0.0015  # the checkerboard card's lowest edge above the plate's top
_CONTENT_OF_KIND = {
    "sample": "material",
    "alignment": "material",
    "white": "white",
    "oecf": "chart",
    "chart": "esser",
    "geometric": "checkerboard",
}


def holder_content(kind: str, tilt_deg: float | None = None) -> str | None:
    """The content key of a frame of ``kind``: ``material``, ``white``, ``chart``,
    ``checkerboard@<tilt>``, or ``None`` for a dark frame."""
    if kind == "dark":
        return None
    if kind not in _CONTENT_OF_KIND:
        raise InputError(f"kind: expected one of {sorted(_CONTENT_OF_KIND)}, got {kind!r}")
    content = _CONTENT_OF_KIND[kind]
    return f"{content}@{float(tilt_deg or 0.0):g}" if content == "checkerboard" else content


def wedge_pose(tilt_deg: float) -> np.ndarray:
    """4x4 pose of the checkerboard (target frame, :func:`checkerboard_target`) in the sample
    frame: tilted about the sample's x axis by ``tilt_deg`` on a wedge, centred over the sample,
    raised so that its lowest edge clears the holder."""
    if not -45.0 <= tilt_deg <= 45.0:
        raise InputError(f"tilt_deg: expected a wedge of -45..45 degrees, got {tilt_deg}")
    half_height = CHECKERBOARD["rows"] * CHECKERBOARD["square_m"] / 2 + CHECKERBOARD["margin_m"]
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_euler("x", tilt_deg, degrees=True).as_matrix()
    pose[2, 3] = half_height * abs(math.sin(math.radians(tilt_deg))) + _CLEARANCE_M
    return pose


def _raised(parts: list[SurfacePart], height_m: float) -> list[SurfacePart]:
    lift = np.eye(4)
    lift[2, 3] = height_m
    return [transformed(part, lift) for part in parts]


def holder_scene_parts(content: str, material: Material | None) -> list[SurfacePart]:
    """The holder with ``content`` (:func:`holder_content`) on it."""
    if content == "material":
        if material is None:
            raise InputError("material: a frame of the sample needs a material")
        extra = list(material.parts)
    elif content == "white":
        extra = _raised(zenith_white_target(2 * PAPER_INNER_HALF_M), _ON_PLATE_M)
    elif content == "chart":
        extra = _raised(colorchecker_chart(CHART_SIZE_M), _ON_PLATE_M)
    elif content == "esser":
        extra = _raised(esser_chart(CHART_SIZE_M), _ON_PLATE_M)
    elif content.startswith("checkerboard@"):
        tilt = float(content.split("@", 1)[1])
        extra = [
            transformed(part, wedge_pose(tilt)) for part in checkerboard_target(**CHECKERBOARD)
        ]
    else:
        raise InputError(f"content: unknown holder content {content!r}")
    return holder_parts() + extra


def chart_geometry(grid: WavelengthGrid) -> tuple[DomeChart, ...]:
    """The charts the RGB cameras photograph for their spectral responses, for a calibration
    store's metadata: the colour checker of the response series (``oecf`` frames) and the Esser
    chart (``chart`` frames), each with its fields' centres and half-size in the sample frame
    and, as its certificate, its reflectances on ``grid`` (the ColorChecker N Ohta's from
    ``colour``; the Esser chart's measured spectra)."""
    charts = (
        ("oecf", "ColorChecker N Ohta (colour-science)", colorchecker_reflectances, 6),
        ("chart", "Esser test chart (isetbio measurements)", esser_reflectances, ESSER_COLUMNS),
    )
    described = []
    for kind, name, reflectances, columns in charts:
        reflectance = reflectances(grid, out_of_range="clamp")
        centres = chart_field_centres(reflectance.values.shape[0], columns, CHART_SIZE_M)
        centres[:, 2] += _ON_PLATE_M
        described.append(
            DomeChart(
                kind=kind,
                name=name,
                columns=columns,
                field_centres_m=centres.tolist(),
                field_half_m=CHART_FILL * CHART_SIZE_M / columns / 2,
                reflectance=Spectrum(
                    wavelengths_nm=grid.wavelengths_nm.tolist(), values=reflectance.values.tolist()
                ),
            )
        )
    return tuple(described)


def holder_geometry() -> DomeHolder:
    """The holder's registration geometry for a store's metadata (:mod:`hwbridge.dome_layout`):
    the print's outer corners in the texture's corner order ``(0,0), (1,0), (1,1), (0,1)``
    (sample ``(-h, +h), (+h, +h), (+h, -h), (-h, -h)``), the print's half-sizes and the
    opening's."""
    return DomeHolder(
        registration_corners_m=registration_corners()[[1, 0, 3, 2]].tolist(),
        print_inner_half_m=PRINT_INNER_HALF_M,
        print_outer_half_m=PRINT_OUTER_HALF_M,
        opening_half_m=PAPER_INNER_HALF_M,
    )


def target_geometry(tilts_deg: list[float]) -> CheckerboardTarget:
    """The checkerboard for a store's metadata: squares, inner corners in the target frame and
    its pose on the wedge for every tilt in ``tilts_deg``."""
    columns, rows = CHECKERBOARD["columns"], CHECKERBOARD["rows"]
    return CheckerboardTarget(
        kind="checkerboard",
        squares=(columns, rows),
        inner_corners=(columns - 1, rows - 1),
        square_m=CHECKERBOARD["square_m"],
        corners_m=checkerboard_corners(columns, rows, CHECKERBOARD["square_m"]).tolist(),
        target_to_sample={f"{tilt:g}": wedge_pose(tilt).tolist() for tilt in tilts_deg},
    )
