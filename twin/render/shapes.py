"""Surface parts (:mod:`twin.materials.surfaces`) and other trimesh meshes as Mitsuba shapes,
built in memory.

Each part's reflectance goes to Mitsuba as an irregular spectrum, so renders and the noise-free
truth use exactly the same spectra.
"""

from __future__ import annotations

import numpy as np
import trimesh

from recon.btf.specular_lobe import COATING_IOR
from recon.errors import InputError
from twin.materials.surfaces import SurfacePart, texture_coordinates
from twin.render.render import load_scene
from twin.render.spectra import irregular_spectrum
from twin.render.variant import activate

__all__ = ["mesh_shape", "mitsuba_shape", "part_bsdf"]


def part_bsdf(part: SurfacePart, *, unit: bool = False) -> dict[str, object]:
    """The Mitsuba BSDF dict of ``part``: its diffuse reflectance, coating, conductor or clear
    dielectric.

    With ``unit`` the same BSDF with every spectral factor one: a reflectance of one and a
    perfectly reflecting metal (Mitsuba's ``material: none``), i.e. the geometric factors of its
    lobes, which :mod:`twin.render.node_transport` multiplies with the spectra itself. A part
    with a spectral texture has only the unit form: Mitsuba's textures are RGB.
    """
    if part.texture is not None and not unit:
        raise InputError(
            f"{part.name}: a spectrally textured part renders through the node transport "
            "(virtual captures and the truth), not in a Mitsuba scene of its own"
        )
    if part.conductor is not None:
        return {
            "type": "roughconductor",
            "material": "none" if unit else part.conductor,
            "alpha": part.roughness or 0.05,
        }
    if part.dielectric_ior is not None:  # no spectral factor: the index is constant
        return {
            "type": "roughdielectric",
            "alpha": part.roughness,
            "int_ior": part.dielectric_ior,
            "ext_ior": 1.0,
        }
    diffuse = {"type": "uniform", "value": 1.0} if unit else irregular_spectrum(part.reflectance)
    if part.roughness is None:
        return {"type": "diffuse", "reflectance": diffuse}
    return {
        "type": "roughplastic",
        "diffuse_reflectance": diffuse,
        "alpha": part.roughness,
        "int_ior": COATING_IOR,
        "nonlinear": False,
    }


def mitsuba_shape(part: SurfacePart, bsdf=None):
    """A Mitsuba mesh built in memory from ``part`` (no files), with its BSDF attached (or
    ``bsdf``, a loaded Mitsuba BSDF that several shapes may share) and, for a textured part,
    its texture coordinates."""
    textured = part.texture is not None
    return mesh_shape(
        part.name,
        part.mesh,
        bsdf if bsdf is not None else load_scene(part_bsdf(part)),
        uv=texture_coordinates(part.mesh) if textured else None,
    )


def mesh_shape(name: str, mesh: trimesh.Trimesh, bsdf=None, *, uv=None, normals: bool = False):
    """A Mitsuba mesh built in memory from a trimesh ``mesh`` (no files).

    Parameters
    ----------
    name
        The shape's id.
    mesh
        Vertices in metres and triangles.
    bsdf
        A loaded Mitsuba BSDF, or ``None`` for Mitsuba's default (diffuse).
    uv
        Per-vertex texture coordinates ``(n_vertices, 2)``, or ``None`` for none (Mitsuba's
        shading frame then does not follow a texture).
    normals
        Give the mesh ``mesh.vertex_normals`` (smooth shading) instead of flat faces.

    Returns
    -------
    mitsuba.Mesh
    """
    activate()
    import mitsuba as mi

    properties = mi.Properties()
    if bsdf is not None:
        properties["bsdf"] = bsdf
    shape = mi.Mesh(
        name,
        len(mesh.vertices),
        len(mesh.faces),
        props=properties,
        has_vertex_normals=normals,
        has_vertex_texcoords=uv is not None,
    )
    parameters = mi.traverse(shape)
    parameters["vertex_positions"] = mi.Float(np.asarray(mesh.vertices, np.float32).ravel())
    parameters["faces"] = mi.UInt32(np.asarray(mesh.faces, np.uint32).ravel())
    if normals:
        parameters["vertex_normals"] = mi.Float(np.asarray(mesh.vertex_normals, np.float32).ravel())
    if uv is not None:
        parameters["vertex_texcoords"] = mi.Float(np.asarray(uv, np.float32).ravel())
    parameters.update()
    return shape
