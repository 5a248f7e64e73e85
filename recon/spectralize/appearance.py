"""Appearance spaces and the appearance-neighbour graph of spectralization (thesis section 6.2).

Every pixel :math:`i` of the RGB image :math:`V` is projected into an appearance space by
:math:`\\pi_{app}` and linked to its :math:`k` nearest neighbours :math:`N_i` there. The prior of
Eq. 6.3 then asks the spectra of linked pixels to be similar. Three projections of the thesis and a
learned one are provided (one function each, registered in :data:`APPEARANCE_SPACES`):

- ``"rgb"``: the identity, Eq. 6.4;
- ``"rgbxy"``: RGB plus scaled pixel coordinates, Eq. 6.5 (the thesis's recommendation);
- ``"patch"``: the RGB values of the :math:`(2m+1)^2` patch around each pixel with the centre
  weighted by :math:`\\alpha_{center} = (2m+1)^2 - 1`, Eq. 6.6;
- ``"learned"``: every pixel's spectrum predicted from patch features around it by a map fitted
  on the known spectra (:mod:`recon.spectralize.learned_appearance`; options ``known_pixels``
  and ``known_spectra``).

The neighbour search uses a kd-tree (pykdtree, queried in the point order of scipy's
``cKDTree``) and enforces the rule of section 6.2,
:math:`\\forall j > i: j \\in N_i \\Rightarrow i \\notin N_j`, so that no link is counted twice
and the graph does not fall apart into small mutually-linked clusters.

A graph component that holds no measured spectrum is undetermined in the camera's metameric-black
subspace (no term of Eq. 6.10 reaches it there). :func:`connect_components` links every such
component to its appearance-nearest pixel in a component that does hold data, with an ordinary
prior link.

References
----------
- The thesis, section 6.2, Eq. 6.3-6.6.
- Maneewongvatana, S., & Mount, D. M. (1999). Analysis of approximate nearest neighbor searching
  with clustered point sets (the sliding-midpoint kd-tree of ``scipy.spatial.cKDTree``).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from pykdtree.kdtree import KDTree
from scipy import ndimage, sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from recon.errors import InputError
from recon.spectralize.learned_appearance import learned_points

__all__ = [
    "APPEARANCE_SPACES",
    "NeighbourGraph",
    "appearance_neighbours",
    "appearance_points",
    "connect_components",
]

_THREADS = 2  # threads of the link rule's rounds
_SPLIT_ROWS = 50_000  # rows of a round above which it is split between them


def _rgb(images: np.ndarray, **_: object) -> np.ndarray:
    """Eq. 6.4: :math:`\\pi^{RGB}_{app} = id`."""
    return images.reshape(-1, images.shape[-1])


def _rgbxy(images: np.ndarray, *, xy_scale: float = 0.25, **_: object) -> np.ndarray:
    """Eq. 6.5: :math:`[V_i, x_i, y_i]`, coordinates scaled to ``xy_scale`` times the mean RGB
    spread (per image side) so that colour dominates and space breaks ties between metamers."""
    count, height, width, _ = images.shape
    rgb = images.reshape(-1, images.shape[-1])
    spread = float(np.mean(np.std(rgb, axis=0))) or 1.0
    rows, cols = np.mgrid[0:height, 0:width]
    side = max(height, width)
    xy = np.stack([cols, rows], axis=-1).reshape(-1, 2) * (xy_scale * spread / side)
    return np.concatenate([rgb, np.tile(xy, (count, 1))], axis=1)


def _patch(images: np.ndarray, *, patch_radius: int = 1, **_: object) -> np.ndarray:
    """Eq. 6.6: the :math:`(2m+1)^2` neighbourhood's RGB, centre weighted by
    :math:`\\alpha_{center} = (2m+1)^2 - 1`; image borders are mirrored."""
    m = int(patch_radius)
    if m < 1:
        raise InputError(f"patch_radius: expected an integer >= 1, got {patch_radius}")
    centre_weight = (2 * m + 1) ** 2 - 1
    padded = np.pad(images, ((0, 0), (m, m), (m, m), (0, 0)), mode="reflect")
    count, height, width, channels = images.shape
    parts = []
    for dy in range(-m, m + 1):
        for dx in range(-m, m + 1):
            shifted = padded[:, m + dy : m + dy + height, m + dx : m + dx + width]
            parts.append(shifted * (centre_weight if dx == dy == 0 else 1.0))
    return np.concatenate(parts, axis=-1).reshape(count * height * width, -1)


APPEARANCE_SPACES: dict[str, Callable[..., np.ndarray]] = {
    "rgb": _rgb,
    "rgbxy": _rgbxy,
    "patch": _patch,
    "learned": learned_points,
}


def appearance_points(images: np.ndarray, space: str = "rgbxy", **options: Any) -> np.ndarray:
    """Project RGB images into an appearance space (thesis Eq. 6.4-6.6).

    Parameters
    ----------
    images
        ``(n_images, height, width, channels)`` camera values (already scaled by :math:`f_i`
        of Eq. 10.2 where dynamic-range compression is used, as section 10.1 requires).
    space
        ``"rgb"``, ``"rgbxy"`` (option ``xy_scale``), ``"patch"`` (option ``patch_radius``) or
        ``"learned"`` (options ``known_pixels``, ``known_spectra`` and ``xy_scale``).

    Returns
    -------
    numpy.ndarray
        ``(n_images * height * width, dims)`` points, pixels in row-major order per image.
    """
    if space not in APPEARANCE_SPACES:
        raise InputError(
            f"appearance: unknown space {space!r}; expected one of {sorted(APPEARANCE_SPACES)}"
        )
    images = np.asarray(images, dtype=np.float64)
    if images.ndim != 4:
        raise InputError(
            f"images: expected (n_images, height, width, channels), got shape {images.shape}"
        )
    return APPEARANCE_SPACES[space](images, **options)


@dataclass(frozen=True)
class NeighbourGraph:
    """Undirected prior links :math:`(i, j), j \\in N_i` of Eq. 6.3 as two index arrays.

    ``first[e]`` is the pixel :math:`i` and ``second[e]`` its neighbour :math:`j`; no pair occurs
    twice. ``added`` counts the links made by :func:`connect_components`.
    """

    first: np.ndarray
    second: np.ndarray
    n_pixels: int
    added: int = 0

    @property
    def n_links(self) -> int:
        """:math:`\\sum_i |N_i|`, the number of prior terms per band (Eq. 6.11)."""
        return int(self.first.size)

    def incidence(self) -> sparse.csr_matrix:
        """``(n_links, n_pixels)`` difference operator: row e is :math:`S_i - S_j`."""
        links = np.arange(self.n_links)
        return sparse.csr_matrix(
            (
                np.repeat([1.0, -1.0], self.n_links),
                (np.concatenate([links, links]), np.concatenate([self.first, self.second])),
            ),
            shape=(self.n_links, self.n_pixels),
        )

    def laplacian(self) -> sparse.csr_matrix:
        """Graph Laplacian :math:`D^T D` of the links (unit weights, :math:`\\gamma_{i,n} = 1`):
        the degree on the diagonal and -1 per link, built from the links directly (repeated
        links add up, as in :math:`D^T D`)."""
        n = self.n_pixels
        degree = np.bincount(self.first, minlength=n) + np.bincount(self.second, minlength=n)
        diagonal = np.arange(n)
        rows = np.concatenate([self.first, self.second, diagonal])
        columns = np.concatenate([self.second, self.first, diagonal])
        values = np.concatenate([np.full(2 * self.n_links, -1.0), degree.astype(np.float64)])
        return sparse.csr_matrix((values, (rows, columns)), shape=(n, n))


def _first_allowed(candidates: np.ndarray, allowed: np.ndarray, k: int) -> np.ndarray:
    """Per row, the first ``k`` allowed candidates in distance order; -1 fills short rows."""
    width = candidates.shape[1]
    order = np.arange(width, dtype=np.int16)
    keys = np.where(allowed, order, order + width)
    keys.sort(axis=1)
    keys = keys[:, :k]
    chosen = np.take_along_axis(candidates, (keys % width).astype(np.intp), axis=1)
    chosen[keys >= width] = -1
    return chosen


def _rule_choices(
    candidates: np.ndarray, lower: np.ndarray, neighbours: np.ndarray, rows: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """One round of :func:`_apply_link_rule` on ``rows``: those whose choice changes, and
    their new choice, from the current ``neighbours`` (read only)."""
    cand, low = candidates[rows], lower[rows]
    linked = neighbours[np.where(low, cand, 0)]  # (rows, candidates, k): N_c per candidate
    back = np.zeros(low.shape, dtype=bool)
    for slot in range(k):
        back |= linked[..., slot] == rows[:, None]
    back &= low
    chosen = _first_allowed(cand, ~back, k)
    differs = (chosen != neighbours[rows]).any(axis=1)
    return rows[differs], chosen[differs]


def _apply_link_rule(candidates: np.ndarray, k: int) -> np.ndarray:
    """Choose :math:`N_j` as the first ``k`` candidates :math:`c` of pixel :math:`j` that do not
    violate the rule of section 6.2 (:math:`c < j` and :math:`j \\in N_c`).

    :math:`N_j` depends on :math:`N_c` for :math:`c < j` only, so a fixed-point iteration that
    revisits just the pixels whose lower-index candidates changed reaches the sequential result.
    Those pixels are read off an index of every pixel's dependants (the higher pixels that have
    it as a candidate), so a round costs in proportion to its changes, not to the image. Each
    round reads the previous round's choices only, so its rows are split between two threads
    (numpy's indexing and sorting release the GIL).
    """
    n = candidates.shape[0]
    pixels = np.arange(n, dtype=candidates.dtype)
    lower = candidates < pixels[:, None]
    dependent, slot = np.nonzero(lower)
    dependants = sparse.csr_matrix(
        (np.ones(dependent.size, dtype=bool), (candidates[dependent, slot], dependent)),
        shape=(n, n),
    )
    neighbours = candidates[:, :k].copy()
    active = pixels
    with ThreadPoolExecutor(_THREADS) as pool:
        while active.size:
            chunks = np.array_split(active, _THREADS if active.size > _SPLIT_ROWS else 1)
            rounds = list(
                pool.map(lambda rows: _rule_choices(candidates, lower, neighbours, rows, k), chunks)
            )
            for changed, chosen in rounds:
                neighbours[changed] = chosen
            marked = np.zeros(n, dtype=bool)
            marked[dependants[np.concatenate([changed for changed, _ in rounds])].indices] = True
            active = np.flatnonzero(marked).astype(pixels.dtype)
    return neighbours


def appearance_neighbours(
    points: np.ndarray, *, k: int = 3, candidates: int | None = None
) -> NeighbourGraph:
    """The :math:`k` appearance neighbours of every point with the rule of section 6.2.

    Parameters
    ----------
    points
        ``(n_pixels, dims)`` appearance points (:func:`appearance_points`).
    k
        Neighbours per pixel, :math:`|N_i|`; the thesis found 3 sufficient.
    candidates
        Nearest points searched per pixel (default ``2 k``); links the rule forbids are
        replaced by the next candidates, so a pixel ends with fewer than ``k`` links only
        where all its candidates are taken.

    Returns
    -------
    NeighbourGraph
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] < 2:
        raise InputError(f"points: expected (n_pixels >= 2, dims), got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise InputError("points: appearance values must be finite (found NaN or inf)")
    n = points.shape[0]
    candidates = 2 * k if candidates is None else int(candidates)
    if not 1 <= k <= candidates < n:
        raise InputError(
            f"k={k}, candidates={candidates}: expected 1 <= k <= candidates < n_pixels={n}"
        )
    # Queries in a kd-tree's own point order keep successive searches in cache (a quarter of
    # the time); pykdtree answers them in 60 % of cKDTree's time, with the same neighbours.
    order = cKDTree(points, balanced_tree=False, compact_nodes=False).indices
    points = np.ascontiguousarray(points)
    _, in_order = KDTree(points, leafsize=16).query(points[order], k=candidates + 1)
    found = np.empty(in_order.shape, dtype=np.int32 if n < 2**31 else np.int64)
    found[order] = in_order
    pixels = np.arange(n, dtype=found.dtype)
    # Drop each pixel itself: the first hit, unless duplicate points came first.
    if np.array_equal(found[:, 0], pixels):
        nearest = found[:, 1:]
    else:
        is_self = found == pixels[:, None]
        drop = np.where(is_self.any(axis=1), np.argmax(is_self, axis=1), candidates)
        keep = np.arange(candidates + 1)[None, :] != drop[:, None]
        nearest = found[keep].reshape(n, candidates)
    neighbours = _apply_link_rule(nearest, k)
    first = np.repeat(pixels, k)
    second = neighbours.ravel()
    valid = second >= 0
    return NeighbourGraph(first[valid], second[valid], n)


def connect_components(
    graph: NeighbourGraph, points: np.ndarray, has_data: np.ndarray
) -> NeighbourGraph:
    """Link every graph component without data to the nearest pixel (in appearance space) of a
    component with data, so that no part of the image is left undetermined.

    Parameters
    ----------
    graph
        Links from :func:`appearance_neighbours`.
    points
        The same ``(n_pixels, dims)`` appearance points.
    has_data
        ``(n_pixels,)`` booleans: pixels that carry a spectral measurement (any data term).

    Returns
    -------
    NeighbourGraph
        ``graph`` with one extra link per data-less component (``added`` counts them).
    """
    has_data = np.asarray(has_data, dtype=bool)
    if has_data.shape != (graph.n_pixels,):
        raise InputError(f"has_data: expected shape ({graph.n_pixels},), got {has_data.shape}")
    if not has_data.any():
        raise InputError("has_data: no pixel carries spectral data; nothing to anchor to")
    adjacency = sparse.csr_matrix(
        (np.ones(graph.n_links), (graph.first, graph.second)),
        shape=(graph.n_pixels, graph.n_pixels),
    )
    count, labels = csgraph.connected_components(adjacency, directed=False)
    anchored = np.zeros(count, dtype=bool)
    anchored[labels[has_data]] = True
    if anchored.all():
        return graph
    inside = np.flatnonzero(anchored[labels])
    outside = np.flatnonzero(~anchored[labels])
    distance, nearest = KDTree(np.ascontiguousarray(points[inside])).query(points[outside], k=1)
    # Per floating component, its pixel closest to any anchored pixel.
    best = ndimage.minimum_position(
        distance, labels=labels[outside], index=np.flatnonzero(~anchored)
    )
    rows = np.array([position[0] for position in best], dtype=np.intp)
    first = np.concatenate([graph.first, outside[rows].astype(graph.first.dtype)])
    second = np.concatenate([graph.second, inside[nearest[rows]].astype(graph.second.dtype)])
    return NeighbourGraph(first, second, graph.n_pixels, graph.added + rows.size)
