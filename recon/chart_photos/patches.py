"""A chart's patches in a photograph: where they are, their mean device RGB, exposures merged.

The chart's four corners in the photograph (pixel coordinates x, y; the corner at the first
patch, then along the first row, then the opposite corner, then the last row's first patch: the
outer corners of the grid of patches) fix a homography from the chart's grid (``columns x
rows`` cells) to the image. Each patch is sampled over the central ``fraction`` of its cell (half
its side by default, clear of the gaps between patches, of chromatic aberration at its edges and
of a few pixels' error in the corners). Its value per channel is the mean of the sites of that
colour inside the window (``recon.chart_patches.patch_statistics``): a raw mosaic is never
demosaiced.

Several exposures of the same chart under the same light merge into one device RGB per patch
and channel (thesis 9.4 needs the linear signal of every patch, dark and bright): each
exposure's mean divided by its exposure time, over the exposures where no site of the window
is clipped and the mean is at least ``floor`` of the white level (darker means are dominated by
noise and by a black level clipped at zero), weighted by exposure time (the sum of the signals
over the sum of the times); a patch too dark in every exposure takes its longest unclipped one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from skimage import draw

from recon.chart_patches import PatchStatistics, patch_statistics
from recon.chart_photos.images import LinearPhoto
from recon.errors import InputError

__all__ = ["MIN_SITES", "MergedPatches", "chart_homography", "merge_exposures", "sample_patches"]

MIN_SITES = 4
"""Fewest sites of each colour in a patch's window."""

_CHANNELS = "RGB"


def chart_homography(corners: np.ndarray, rows: int, columns: int) -> np.ndarray:
    """``(3, 3)`` homography from chart coordinates (u along a row in ``[0, columns]``, v down
    the chart in ``[0, rows]``) to pixel coordinates (x, y), from the four corners ``(4, 2)``
    (module description)."""
    source = np.array([[0, 0], [columns, 0], [columns, rows], [0, rows]], np.float64)
    system = []
    target = []
    for (u, v), (x, y) in zip(source, corners, strict=True):
        system.append([u, v, 1, 0, 0, 0, -u * x, -v * x])
        system.append([0, 0, 0, u, v, 1, -u * y, -v * y])
        target.extend([x, y])
    solution = np.linalg.solve(np.array(system), np.array(target))
    return np.append(solution, 1.0).reshape(3, 3)


def _check_corners(corners: np.ndarray, shape: tuple[int, int], source: str) -> np.ndarray:
    corners = np.asarray(corners, np.float64)
    if corners.shape != (4, 2) or not np.all(np.isfinite(corners)):
        raise InputError(f"corners: expected 4 points (x, y) in pixels, got {corners.tolist()}")
    height, width = shape
    for number, (x, y) in enumerate(corners, start=1):
        if not (0 <= x <= width - 1 and 0 <= y <= height - 1):
            raise InputError(
                f"corners: corner {number} ({x:g}, {y:g}) lies outside {source} of {width} x "
                f"{height} px; expected x in [0, {width - 1}], y in [0, {height - 1}]"
            )
    edges = np.roll(corners, -1, axis=0) - corners
    turns = (
        edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, 0)[:, 0]
    )
    if not (np.all(turns > 0) or np.all(turns < 0)):
        raise InputError(
            f"corners: {corners.tolist()} is not a convex quadrilateral; expected the chart's "
            "corners in order around it, the first at its first patch"
        )
    return corners


def sample_patches(
    photo: LinearPhoto,
    corners: np.ndarray,
    rows: int,
    columns: int,
    *,
    fraction: float = 0.5,
) -> PatchStatistics:
    """The statistics per patch and channel of one photograph (module description).

    Parameters
    ----------
    photo
        The photograph, linear.
    corners
        ``(4, 2)`` the chart's outer corners in pixels (x, y), in order around it, the first at
        the first patch.
    rows, columns
        The chart's layout.
    fraction
        Side of the sampled window over that of the patch's cell.

    Returns
    -------
    PatchStatistics
        Mean, spread, clipped fraction and number of sites, ``(rows * columns, 3)`` each.
    """
    if not 0 < fraction <= 1:
        raise InputError(f"fraction: expected a value in (0, 1], got {fraction}")
    corners = _check_corners(corners, photo.shape, photo.source)
    homography = chart_homography(corners, rows, columns)
    half = fraction / 2
    shape = (rows * columns, 3)
    statistics = [np.full(shape, np.nan) for _ in range(4)]
    for patch in range(rows * columns):
        row, column = divmod(patch, columns)
        cell = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
        window = _to_pixels(homography, cell + [column + 0.5, row + 0.5])
        low = np.maximum(np.floor(window.min(axis=0)).astype(int), 0)
        high = np.ceil(window.max(axis=0)).astype(int) + 1
        crop = (slice(low[1], high[1]), slice(low[0], high[0]))
        mask = draw.polygon2mask((high[1] - low[1], high[0] - low[0]), window[:, ::-1] - low[::-1])
        for channel in range(3):
            values, sites = photo.channel(channel, crop)
            found = patch_statistics(
                values, mask[None], np.where(sites, 0, -1), top_dn=photo.white_level
            )
            for array, value in zip(
                statistics, (found.mean, found.spread, found.clipped, found.pixels), strict=True
            ):
                array[patch, channel] = value[0, 0]
    pixels = statistics[3]
    if pixels.min() < MIN_SITES:
        fewest, colour_index = (int(i) for i in np.unravel_index(np.argmin(pixels), pixels.shape))
        raise InputError(
            f"corners: patch {fewest + 1}'s window in {photo.source} holds {pixels.min():.0f} "
            f"{_CHANNELS[colour_index]} sites; expected at least {MIN_SITES} (a larger chart in "
            "the image, or corners around the chart's patches)"
        )
    return PatchStatistics(*statistics)


def _to_pixels(homography: np.ndarray, points: np.ndarray) -> np.ndarray:
    mapped = np.column_stack([points, np.ones(len(points))]) @ homography.T
    return mapped[:, :2] / mapped[:, 2:]


@dataclass(frozen=True)
class MergedPatches:
    """Device RGB per patch and channel ``(J, 3)`` per second of exposure, and how many of the
    exposures went into each."""

    rgb: np.ndarray
    exposures_used: np.ndarray


def merge_exposures(
    statistics: Sequence[PatchStatistics],
    exposure_s: Sequence[float],
    *,
    white_level: float,
    floor: float = 0.02,
    source: str = "the photographs",
) -> MergedPatches:
    """Merge exposures of one chart under one light (module description).

    Parameters
    ----------
    statistics
        :func:`sample_patches` of each photograph.
    exposure_s
        Each photograph's exposure time in seconds (any common unit).
    white_level
        The photographs' white level (for the ``floor``).
    floor
        Fraction of the white level below which an exposure is left out of the merge where a
        brighter one is unclipped.
    source
        What the photographs are, for the messages.
    """
    times = np.asarray(exposure_s, np.float64)
    if len(statistics) != times.size or times.size == 0 or not np.all(times > 0):
        raise InputError(f"exposure_s: expected one positive time per photograph of {source}")
    means = np.array([s.mean for s in statistics])  # (E, J, 3)
    unclipped = np.array([s.clipped == 0 for s in statistics])
    if not np.all(unclipped.any(axis=0)):
        patch, channel = np.argwhere(~unclipped.any(axis=0))[0]
        raise InputError(
            f"{source}: patch {patch + 1} is clipped in {_CHANNELS[channel]} in every exposure; "
            "expected at least one exposure where none of its sites reaches the white level"
        )
    threshold = floor * white_level if np.isfinite(white_level) else 0.0
    used = unclipped & (means >= threshold)
    longest = np.argmax(np.where(unclipped, times[:, None, None], -1.0), axis=0)
    fallback = ~used.any(axis=0)
    used[longest[fallback], *np.nonzero(fallback)] = True
    weights = np.where(used, times[:, None, None], 0.0)
    rgb = np.sum(np.where(used, means, 0.0), axis=0) / np.sum(weights, axis=0)
    return MergedPatches(rgb=rgb, exposures_used=used.sum(axis=0))
