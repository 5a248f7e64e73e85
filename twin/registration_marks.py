"""Find the sample holder's registration corners in an image (outer corners of the black print).

Used to check the rig kinematics against renders (and, later, to register frames): the dark
print band between white paper is segmented, its outer boundary traced with sub-pixel contours of
the image, and each side fitted with a line; adjacent sides intersect in the corners.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from skimage import measure

from recon.errors import SpectwinInputError

__all__ = ["find_print_corners"]


def _intersect(
    first: tuple[np.ndarray, np.ndarray], second: tuple[np.ndarray, np.ndarray]
) -> np.ndarray:
    (p, d), (q, e) = first, second
    steps = np.linalg.solve(np.column_stack([d, -e]), q - p)
    return p + steps[0] * d


def find_print_corners(image: np.ndarray, expected_xy: np.ndarray) -> np.ndarray:
    """Sub-pixel (column, row) of the print's four outer corners, ordered like ``expected_xy``.

    Parameters
    ----------
    image
        Single-channel intensity image ``(H, W)`` with the holder in view.
    expected_xy
        Approximate corner positions ``(4, 2)`` in the same convention (pixel centres at +0.5),
        consecutive corners sharing a side; used only to tell the four sides apart.
    """
    image = np.asarray(image, np.float64)
    paper = np.percentile(image, 99)
    dark = image < 0.25 * paper
    labels, count = ndimage.label(dark)
    touching = set(np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])))
    candidates = [label for label in range(1, count + 1) if label not in touching]
    if not candidates:
        raise SpectwinInputError("image: no dark print band enclosed by paper was found")
    sizes = ndimage.sum(dark, labels, candidates)
    band = ndimage.binary_fill_holes(labels == candidates[int(np.argmax(sizes))])
    outer_edge = band ^ ndimage.binary_erosion(band)
    near_edge = ndimage.binary_dilation(outer_edge, iterations=2)
    level = 0.5 * (np.median(image[band & dark]) + paper)
    points = np.concatenate(measure.find_contours(image, level)) + 0.5  # (row, column)
    rows, columns = np.clip(points.astype(int), 0, np.array(image.shape) - 1).T
    points = points[near_edge[rows, columns]][:, ::-1]  # (column, row)
    expected = np.asarray(expected_xy, np.float64)
    sides = []
    for index in range(4):
        start, end = expected[index], expected[(index + 1) % 4]
        direction = (end - start) / np.linalg.norm(end - start)
        offsets = points - start
        along = offsets @ direction
        across = np.abs(offsets @ np.array([-direction[1], direction[0]]))
        length = np.linalg.norm(end - start)
        chosen = points[(across < 3) & (along > 0.15 * length) & (along < 0.85 * length)]
        if len(chosen) < 5:
            raise SpectwinInputError(f"image: side {index} of the print could not be traced")
        line = measure.LineModelND.from_estimate(chosen)  # total least squares
        sides.append((line.origin, line.direction))
    return np.array([_intersect(sides[index - 1], sides[index]) for index in range(4)])
