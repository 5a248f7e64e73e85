"""Geometry with spectral materials: trimesh meshes, each with one reflectance.

A sample, a sample holder or a target is a list of :class:`SurfacePart`: one mesh and one
material each, with the material's spectral reflectance given explicitly on a wavelength grid so
that renders and the noise-free truth use exactly the same spectra. Parts with a single
reflectance need no texture, which Mitsuba only offers in RGB. :mod:`twin.render.shapes` turns
them into Mitsuba shapes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from recon.errors import SpectwinInputError
from recon.spectra import SampledSpectra

__all__ = ["SurfacePart", "transformed"]


@dataclass(frozen=True, eq=False)
class SurfacePart:
    """A mesh with one material.

    Parameters
    ----------
    name
        Identifier (also the Mitsuba shape id).
    mesh
        Geometry in metres, in the frame of its owner (sample frame: z is the normal).
    reflectance
        Diffuse spectral reflectance (1-D values in [0, 1]).
    roughness
        ``None`` for a Lambertian surface; otherwise the GGX roughness of a dielectric coating
        (index 1.5) over the diffuse base (Mitsuba ``roughplastic``): a glossy material.
    conductor
        A Mitsuba conductor preset (e.g. ``"Ag"``, ``"Al"``) instead of the diffuse base; its
        spectral reflectance then follows from the metal's complex index (Fresnel).
    """

    name: str
    mesh: trimesh.Trimesh
    reflectance: SampledSpectra
    roughness: float | None = None
    conductor: str | None = None

    def __post_init__(self) -> None:
        if self.reflectance.values.ndim != 1:
            raise SpectwinInputError(f"{self.name}: expected one reflectance spectrum")
        values = self.reflectance.values
        if np.any(values < 0) or np.any(values > 1):
            raise SpectwinInputError(f"{self.name}: expected reflectance values in [0, 1]")
        if self.roughness is not None and not 0 < self.roughness <= 1:
            raise SpectwinInputError(
                f"{self.name}: expected roughness in (0, 1], got {self.roughness}"
            )
        if len(self.mesh.faces) == 0:
            raise SpectwinInputError(f"{self.name}: the mesh has no faces")


def transformed(part: SurfacePart, matrix: np.ndarray) -> SurfacePart:
    """A copy of ``part`` with its mesh moved by a 4x4 homogeneous ``matrix``."""
    mesh = part.mesh.copy()
    mesh.apply_transform(matrix)
    return SurfacePart(part.name, mesh, part.reflectance, part.roughness, part.conductor)
