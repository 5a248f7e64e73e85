"""Where rays first meet a triangle mesh, by Mitsuba's ray tracer (no render): the points and
the shading normals there, as the renderer shades them.
"""

from __future__ import annotations

import numpy as np
import trimesh

from twin.render.render import load_scene
from twin.render.shapes import mesh_shape
from twin.render.variant import activate

__all__ = ["first_hits"]


def first_hits(
    mesh: trimesh.Trimesh, origins: np.ndarray, directions: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first intersections of rays with ``mesh`` (smoothly shaded by its vertex normals).

    Parameters
    ----------
    mesh
        Vertices in metres, triangles and ``vertex_normals``.
    origins, directions
        The rays, ``(n, 3)`` each (directions of unit length).

    Returns
    -------
    tuple of numpy.ndarray
        ``hit`` ``(n,)`` (bool), and for the rays that hit, in their order, the ``points``
        ``(m, 3)`` and the unit shading ``normals`` ``(m, 3)`` (the vertex normals interpolated;
        on the side they point to, whichever side the ray meets).

    Examples
    --------
    >>> square = trimesh.Trimesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
    ...                          [[0, 1, 2], [0, 2, 3]])
    >>> hit, points, normals = first_hits(square, np.array([[0.5, 0.25, 2], [3, 0, 2]]),
    ...                                   np.array([[0, 0, -1.0], [0, 0, -1]]))
    >>> hit.tolist(), points.round(3).tolist(), normals.round(3).tolist()
    ([True, False], [[0.5, 0.25, 0.0]], [[0.0, 0.0, 1.0]])
    """
    activate()
    import mitsuba as mi

    scene = load_scene({"type": "scene", "surface": mesh_shape("surface", mesh, normals=True)})
    origins, directions = (np.asarray(a, np.float32) for a in (origins, directions))
    ray = mi.Ray3f(mi.Point3f(*origins.T), mi.Vector3f(*directions.T))
    interaction = scene.ray_intersect(ray)
    hit = np.asarray(interaction.is_valid(), bool)
    points = np.asarray(interaction.p, np.float64).reshape(3, -1).T
    normals = np.asarray(interaction.sh_frame.n, np.float64).reshape(3, -1).T
    return hit, points[hit], normals[hit]
