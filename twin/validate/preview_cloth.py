"""The cloth of the BTF preview (``spectwin btf render --shape cloth``): a sheet hanging over a
rod, with soft folds, as a triangle mesh with texture coordinates and smooth normals.

The sheet is :data:`CLOTH_TILES` tiles of :data:`TILE_M` square (across the rod, along the
drape): the BTF's texture is repeated once per tile, each tile's texture coordinates spanning
``[0, 1]`` (vertices on the tiles' seams are repeated with each tile's coordinates), so a texel
covers about what it does on the preview's plane. The rod, of radius :data:`ROD_RADIUS_M`, lies
along +x at the height :data:`ROD_HEIGHT_M`; the sheet's middle lies over its top, and both
halves hang straight down from it, the front (towards the camera, -y) and the back, their hem
just above the ground. A hanging half folds: it is displaced along its normal by a sum of two
sines across the sheet (2.5 and 4 periods over its width, other phases behind), growing
smoothly from nothing where it leaves the rod to :data:`FOLD_DEPTH_M` at the hem. The folds
take up cloth: every row across the sheet keeps its length (the texture is not stretched
across the folds) and is gathered narrower instead.

Texture coordinates follow the sample frame of a BTF: ``u`` along +x, ``v`` up the front
half, over the rod and down the back, so that ``dp/du x dp/dv`` is the outward normal and the
texture's top row is up on the side the camera sees, as on the plane. The vertex normals are
the area-weighted face normals of the sheet before its tiles are cut apart (trimesh), so they
are smooth across the seams.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import trimesh

__all__ = [
    "CLOTH_TILES",
    "FOLD_DEPTH_M",
    "ROD_HEIGHT_M",
    "ROD_RADIUS_M",
    "TILE_M",
    "cloth_mesh",
]

TILE_M = 0.04
"""Side of one repeat of the BTF's texture on the cloth."""
CLOTH_TILES = (3, 5)
"""Tiles across the rod and along the drape: a sheet of 0.12 m x 0.2 m."""
ROD_RADIUS_M = 0.02
"""Radius of the sheet's bend over the rod."""
ROD_HEIGHT_M = 0.02
"""Height of the rod's axis: the sheet's top at 0.04 m, its hem 2.4 mm above the ground."""
FOLD_DEPTH_M = 0.006
"""Depth of the folds at the hem."""
_CELLS_PER_TILE = 20
_FOLDS = ((0.6, 2.5, 0.0, 1.3), (0.4, 4.0, 1.0, 3.6))
"""The folds' two sines: amplitude, periods over the sheet's width, phase in front, behind."""


def _grid_faces(rows: int, columns: int) -> np.ndarray:
    """Two triangles per cell of a ``rows x columns`` vertex grid (row-major), wound so that
    their normal is (towards the next column) x (towards the next row)."""
    corner = (np.arange(rows - 1)[:, None] * columns + np.arange(columns - 1)[None, :]).ravel()
    right, below = corner + 1, corner + columns
    return np.concatenate(
        [np.stack([corner, right, below + 1], axis=1), np.stack([corner, below + 1, below], 1)]
    )


def _centre_line(drape_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(n, 2)`` (y, z) and outward normals ``(n, 2)`` of the sheet's cross-section at
    ``drape_m`` from its top (negative: the front half)."""
    bend_m = np.pi * ROD_RADIUS_M / 2
    angle = np.clip(drape_m, -bend_m, bend_m) / ROD_RADIUS_M
    normals = np.stack([np.sin(angle), np.cos(angle)], axis=1)
    hanging = np.maximum(np.abs(drape_m) - bend_m, 0.0)
    points = ROD_RADIUS_M * normals + np.stack(
        [np.zeros_like(hanging), ROD_HEIGHT_M - hanging], axis=1
    )
    return points, normals


def _fold(x_m: np.ndarray, behind: bool) -> np.ndarray:
    """The folds' profile across the sheet, between -1 and 1."""
    width = CLOTH_TILES[0] * TILE_M
    return np.sum(
        [
            amplitude * np.sin(2 * np.pi * periods * x_m / width + (back if behind else front))
            for amplitude, periods, front, back in _FOLDS
        ],
        axis=0,
    )


def _sheet() -> np.ndarray:
    """The sheet's vertices on one grid ``(rows, columns, 3)``: rows along the drape from the
    front hem, columns across the rod."""
    across, along = (tiles * _CELLS_PER_TILE + 1 for tiles in CLOTH_TILES)
    width, length = (tiles * TILE_M for tiles in CLOTH_TILES)
    drape = np.linspace(-length / 2, length / 2, along)
    points, normals = _centre_line(drape)
    bend_m = np.pi * ROD_RADIUS_M / 2
    ramp = np.clip((np.abs(drape) - bend_m) / (length / 2 - bend_m), 0.0, 1.0)
    depth = FOLD_DEPTH_M * ramp**2 * (3 - 2 * ramp)
    fine = np.linspace(-width / 2, width / 2, 50 * across)
    material = np.linspace(-width / 2, width / 2, across)
    vertices = np.empty((along, across, 3))
    for row in range(along):
        profile = depth[row] * _fold(fine, drape[row] > 0)
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(fine), np.diff(profile)))])
        x = np.interp(arc[-1] / 2 + material, arc, fine)
        offset = depth[row] * _fold(x, drape[row] > 0)
        vertices[row, :, 0] = x
        vertices[row, :, 1:] = points[row] + offset[:, None] * normals[row]
    return vertices


@cache
def cloth_mesh() -> trimesh.Trimesh:
    """The cloth (module docstring): vertices in metres, per-vertex texture coordinates
    (``mesh.visual.uv``) and smooth unit normals (``mesh.vertex_normals``).

    Returns
    -------
    trimesh.Trimesh
        Not processed (the seams' repeated vertices kept); treat it as read-only.
    """
    sheet = _sheet()
    along, across = sheet.shape[:2]
    whole = trimesh.Trimesh(sheet.reshape(-1, 3), _grid_faces(along, across), process=False)
    normals = whole.vertex_normals
    side = _CELLS_PER_TILE + 1
    local = np.arange(side)
    tiles_across, tiles_along = CLOTH_TILES
    rows = (np.arange(tiles_along)[:, None] * _CELLS_PER_TILE + local)[:, None, :, None]
    columns = (np.arange(tiles_across)[:, None] * _CELLS_PER_TILE + local)[None, :, None, :]
    index = np.broadcast_to(rows * across + columns, (tiles_along, tiles_across, side, side))
    fraction = local / _CELLS_PER_TILE
    u, v = np.meshgrid(fraction, fraction)
    uv = np.broadcast_to(np.stack([u, v], axis=-1), (*index.shape, 2)).reshape(-1, 2)
    tile_faces = _grid_faces(side, side)
    faces = np.concatenate(
        [tile_faces + tile * side * side for tile in range(tiles_along * tiles_across)]
    )
    flat = index.reshape(-1)
    return trimesh.Trimesh(
        sheet.reshape(-1, 3)[flat],
        faces,
        vertex_normals=normals[flat],
        visual=trimesh.visual.TextureVisuals(uv=uv),
        process=False,
    )
