"""The sample holder of the gonioreflectometer and the dome (thesis 4.1.1, 4.1.2, Fig. 4.1).

A metal frame around a plastic plate of about 6 cm; the material sits in the middle of the plate,
surrounded by white paper with a black printed square band whose outer corners are the
registration marks. Everything is in the sample frame (z is the plate normal, the plate's top at
z = 0, the origin at its centre).
"""

from __future__ import annotations

import numpy as np
import trimesh

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.materials.geometry import box
from twin.materials.surfaces import SurfacePart

__all__ = ["PRINT_OUTER_HALF_M", "holder_parts", "registration_corners"]

PLATE_HALF_M = 0.030
PAPER_INNER_HALF_M = 0.0205
PRINT_INNER_HALF_M = 0.0225
PRINT_OUTER_HALF_M = 0.0265
FRAME_OUTER_HALF_M = 0.045
_PAPER_Z, _PRINT_Z = 0.0002, 0.00022  # a 20 um print: its side wall must not shift the corners


def _flat(value: float) -> SampledSpectra:
    return SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, value))


def _square_ring(
    name: str, inner: float, outer: float, z_low: float, z_high: float, reflectance: SampledSpectra
):
    """Four boxes forming a square ring between half-sizes ``inner`` and ``outer``."""
    width, centre, height = outer - inner, (outer + inner) / 2, z_high - z_low
    z = (z_low + z_high) / 2
    meshes = [
        box((0, centre, z), (2 * outer, width, height)),
        box((0, -centre, z), (2 * outer, width, height)),
        box((centre, 0, z), (width, 2 * inner, height)),
        box((-centre, 0, z), (width, 2 * inner, height)),
    ]
    # trimesh types the result as any Geometry (or a list); for meshes it is one Trimesh
    return SurfacePart(name, trimesh.util.concatenate(meshes), reflectance)  # type: ignore[arg-type]


def holder_parts() -> list[SurfacePart]:
    """Frame (painted metal), plate (white plastic), paper border and its black print."""
    return [
        _square_ring("holder_frame", PLATE_HALF_M, FRAME_OUTER_HALF_M, -0.006, 0.001, _flat(0.25)),
        SurfacePart(
            "holder_plate",
            box((0, 0, -0.0015), (2 * PLATE_HALF_M, 2 * PLATE_HALF_M, 0.003)),
            _flat(0.7),
        ),
        _square_ring("holder_paper", PAPER_INNER_HALF_M, PLATE_HALF_M, 0.0, _PAPER_Z, _flat(0.85)),
        _square_ring(
            "holder_print", PRINT_INNER_HALF_M, PRINT_OUTER_HALF_M, _PAPER_Z, _PRINT_Z, _flat(0.03)
        ),
    ]


def registration_corners() -> np.ndarray:
    """Outer corners of the black print, ``(4, 3)`` in the sample frame (counter-clockwise)."""
    half = PRINT_OUTER_HALF_M
    return np.array(
        [
            [half, half, _PRINT_Z],
            [-half, half, _PRINT_Z],
            [-half, -half, _PRINT_Z],
            [half, -half, _PRINT_Z],
        ]
    )
