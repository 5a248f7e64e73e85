"""Geometry with spectral materials: trimesh meshes, each with one reflectance.

A sample, a sample holder or a target is a list of :class:`SurfacePart`: one mesh and one
material each, with the material's spectral reflectance given explicitly on a wavelength grid so
that renders and the noise-free truth use exactly the same spectra. A part may instead carry a
spectral texture (one reflectance spectrum per texel, looked up through the mesh's texture
coordinates), which the node transport (:mod:`twin.render.node_transport`) evaluates itself:
Mitsuba's own textures are RGB. :mod:`twin.render.shapes` turns parts into Mitsuba shapes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import trimesh

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["MATERIAL_GRID", "SurfacePart", "texture_coordinates", "transformed"]

MATERIAL_GRID = WavelengthGrid.regular(380.0, 780.0, 5.0)
"""Grid the material spectra are designed on; they are linear between its samples."""


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
        ``None`` for a Lambertian surface; otherwise the Beckmann roughness of a dielectric
        coating (index 1.5) over the diffuse base (Mitsuba ``roughplastic``): a glossy material.
    conductor
        A Mitsuba conductor preset (e.g. ``"Ag"``, ``"Al"``) instead of the diffuse base; its
        spectral reflectance then follows from the metal's complex index (Fresnel).
    dielectric_ior
        The index of a clear dielectric with no diffuse base (Mitsuba ``roughdielectric``, of
        ``roughness``): it reflects and transmits, and ``reflectance`` is unused.
    texture
        ``None``, or the diffuse reflectance per texel ``(H, W, K)`` (row 0 at the top, texture
        coordinate v = 1; column 0 at u = 0), which then replaces ``reflectance`` in renders;
        ``reflectance`` is its mean. The mesh must carry per-vertex texture coordinates
        (``mesh.visual.uv``).
    """

    name: str
    mesh: trimesh.Trimesh
    reflectance: SampledSpectra
    roughness: float | None = None
    conductor: str | None = None
    texture: SampledSpectra | None = None
    dielectric_ior: float | None = None

    def __post_init__(self) -> None:
        if self.reflectance.values.ndim != 1:
            raise InputError(f"{self.name}: expected one reflectance spectrum")
        values = self.reflectance.values
        if np.any(values < 0) or np.any(values > 1):
            raise InputError(f"{self.name}: expected reflectance values in [0, 1]")
        if self.roughness is not None and not 0 < self.roughness <= 1:
            raise InputError(f"{self.name}: expected roughness in (0, 1], got {self.roughness}")
        if self.dielectric_ior is not None and (
            self.roughness is None or self.conductor is not None or not self.dielectric_ior > 1
        ):
            raise InputError(
                f"{self.name}: a clear dielectric needs an index above 1 and a roughness, and "
                "is no conductor"
            )
        if len(self.mesh.faces) == 0:
            raise InputError(f"{self.name}: the mesh has no faces")
        if self.texture is not None:
            self._check_texture(self.texture.values)

    def _check_texture(self, values: np.ndarray) -> None:
        if values.ndim != 3 or min(values.shape[:2]) < 1:
            raise InputError(
                f"{self.name}: expected a texture of shape (height, width, wavelengths), got "
                f"{values.shape}"
            )
        if np.any(values < 0) or np.any(values > 1):
            raise InputError(f"{self.name}: expected texture reflectances in [0, 1]")
        if self.conductor is not None or self.dielectric_ior is not None:
            raise InputError(
                f"{self.name}: a conductor or clear dielectric takes no diffuse texture"
            )
        uv = texture_coordinates(self.mesh)
        if uv is None or len(uv) != len(self.mesh.vertices):
            raise InputError(
                f"{self.name}: a textured part needs texture coordinates on every mesh vertex"
            )

    @property
    def bsdf_kind(self) -> str:
        """``"diffuse"``, ``"rough plastic"``, ``"rough conductor"`` or ``"rough dielectric"``."""
        if self.conductor is not None:
            return "rough conductor"
        if self.dielectric_ior is not None:
            return "rough dielectric"
        return "diffuse" if self.roughness is None else "rough plastic"

    @property
    def texels(self) -> tuple[int, int]:
        """``(height, width)`` of the texture; ``(1, 1)`` for one reflectance."""
        return (1, 1) if self.texture is None else self.texture.values.shape[:2]


def texture_coordinates(mesh: trimesh.Trimesh) -> np.ndarray | None:
    """The mesh's per-vertex texture coordinates ``(n_vertices, 2)``, or ``None``."""
    uv = getattr(mesh.visual, "uv", None)
    return None if uv is None else np.asarray(uv, np.float64)


def transformed(part: SurfacePart, matrix: np.ndarray) -> SurfacePart:
    """A copy of ``part`` with its mesh moved by a 4x4 homogeneous ``matrix``."""
    mesh = part.mesh.copy()
    mesh.apply_transform(matrix)
    return replace(part, mesh=mesh)
