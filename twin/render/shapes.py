"""Surface parts (:mod:`twin.materials.surfaces`) as Mitsuba shapes, built in memory.

Each part's reflectance goes to Mitsuba as an irregular spectrum, so renders and the noise-free
truth use exactly the same spectra.
"""

from __future__ import annotations

import numpy as np

from recon.btf.specular_lobe import COATING_IOR
from recon.errors import InputError
from twin.materials.surfaces import SurfacePart, texture_coordinates
from twin.render.render import load_scene
from twin.render.spectra import irregular_spectrum
from twin.render.variant import activate

__all__ = ["mitsuba_shape", "part_bsdf"]


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
    activate()
    import mitsuba as mi

    properties = mi.Properties()
    properties["bsdf"] = bsdf if bsdf is not None else load_scene(part_bsdf(part))
    textured = part.texture is not None
    mesh = mi.Mesh(
        part.name,
        len(part.mesh.vertices),
        len(part.mesh.faces),
        props=properties,
        has_vertex_normals=False,
        has_vertex_texcoords=textured,
    )
    parameters = mi.traverse(mesh)
    parameters["vertex_positions"] = mi.Float(np.asarray(part.mesh.vertices, np.float32).ravel())
    parameters["faces"] = mi.UInt32(np.asarray(part.mesh.faces, np.uint32).ravel())
    if textured:
        uv = texture_coordinates(part.mesh)
        parameters["vertex_texcoords"] = mi.Float(np.asarray(uv, np.float32).ravel())
    parameters.update()
    return mesh
