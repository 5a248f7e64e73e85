"""Mesh building blocks for ground-truth materials: tubes for threads, height fields, boxes."""

from __future__ import annotations

import numpy as np
import trimesh

__all__ = ["box", "height_field", "tube"]


def box(centre: tuple[float, float, float], extents: tuple[float, float, float]) -> trimesh.Trimesh:
    """Axis-aligned box of ``extents`` (metres) around ``centre``."""
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def tube(path: np.ndarray, radius: float, sides: int = 8) -> trimesh.Trimesh:
    """Closed-ring tube of ``radius`` around the polyline ``path`` ``(n, 3)`` (open ends)."""
    path = np.asarray(path, dtype=np.float64)
    tangents = np.gradient(path, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    helper = np.where(np.abs(tangents[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    normal = np.cross(tangents, helper)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangents, normal)
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    rings = (
        path[:, None, :]
        + radius * np.cos(angles)[None, :, None] * normal[:, None, :]
        + radius * np.sin(angles)[None, :, None] * binormal[:, None, :]
    )
    vertices = rings.reshape(-1, 3)
    faces = []
    for i in range(len(path) - 1):
        for j in range(sides):
            a, b = i * sides + j, i * sides + (j + 1) % sides
            c, d = a + sides, b + sides
            faces += [[a, b, d], [a, d, c]]
    return trimesh.Trimesh(vertices, np.array(faces), process=False)


def height_field(heights: np.ndarray, size_m: float) -> trimesh.Trimesh:
    """Triangulated height field over the square ``[-size/2, size/2]^2``; ``heights`` ``(n, n)``."""
    count = heights.shape[0]
    coordinates = np.linspace(-size_m / 2, size_m / 2, count)
    x, y = np.meshgrid(coordinates, coordinates, indexing="xy")
    vertices = np.column_stack([x.ravel(), y.ravel(), heights.ravel()])
    index = np.arange(count * count).reshape(count, count)
    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()
    c, d = index[1:, :-1].ravel(), index[1:, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return trimesh.Trimesh(vertices, faces, process=False)
