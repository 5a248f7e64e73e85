"""Registration of the sample holder's border in gonioreflectometer frames (thesis 4.1.2).

The extrinsic camera parameters of the gonioreflectometer are not known to sub-pixel accuracy,
so every raw frame is registered from the border printed around the material: its four corners
are detected, refined to sub-pixel accuracy, and a homography maps the sample area to texture
space, where the textures are extracted by bilinear interpolation. The detection follows the
steps of the thesis:

1. Generate a binary image by thresholding the frame.
2. Construct a list of all outer contours in the binary image (``skimage.measure.find_contours``
   on the padded binary image; contours winding around foreground are the outer ones).
3. Remove all contours having a bounding box of inadequate size.
4. For all contours: (a) local PCA [KL97] of the contour points with 6 clusters and one principal
   component, i.e. 6 lines fitted to the points; (b) remove the two smallest clusters; (c)
   intersect the four remaining lines where the angle between them is larger than 10 degrees.
5. Remove all quadrilaterals having inadequate size.
6. If none remain, reduce the threshold and continue at step 1.

The coarse corners are then refined in texture space (:mod:`recon.registration.corners`). Frames
where the detection fails (strong Fresnel reflections at grazing angles, thesis Figure 4.1(c)) get
their corners from a manual corner file (:func:`read_manual_corners`), the counterpart of the
thesis's corner selection tool.

Which corners are registered is set by ``marks``: ``"dark"`` finds the outer corners of a dark
region surrounded by bright paper (the outer corners of the black print on the twin's sample
holder, ``twin.materials.sample_holder.registration_corners``); ``"bright"`` the corners of a
bright region
surrounded by dark print (the thesis's white border).

Conventions: image points ``(x, y)`` = (column, row), pixel centres at ``+0.5``; corners ordered
like :data:`recon.registration.corners.TEXTURE_CORNERS_UV` (texture ``(0,0), (1,0), (1,1), (0,1)``).

Manual corner file (JSON)::

    {
      "version": 1,
      "comment": "optional free text",
      "frames": {
        "<frame id>": [[x0, y0], [x1, y1], [x2, y2], [x3, y3]],
        ...
      }
    }

Each frame id (a non-empty string, e.g. ``"view12_light40"``) maps to its four image corners in
the convention above, in texture order; they are used as given, without refinement.

References
----------
- The thesis, section 4.1.2 "Post-Processing", Figure 4.1.
- [KL97] Kambhatla, N., & Leen, T. K. (1997). Dimension reduction by local principal component
  analysis. Neural Computation, 9(7), 1493-1516. doi:10.1162/neco.1997.9.7.1493
- [CV01] Chan, T. F., & Vese, L. A. (2001). Active contours without edges. IEEE Transactions on
  Image Processing, 10(2), 266-277. doi:10.1109/83.902291
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, NamedTuple

import numpy as np
from skimage import measure, transform

from recon.errors import InputError
from recon.registration.corners import (
    TEXTURE_CORNERS_UV,
    frame_intensity,
    refine_corners,
    texture_transform,
    validate_corners,
    validate_frame,
    validate_marks,
)

__all__ = [
    "TEXTURE_CORNERS_UV",
    "CornerDetection",
    "MarksNotFoundError",
    "detect_corners",
    "extract_texture",
    "local_pca_lines",
    "order_corners",
    "parse_manual_corners",
    "read_manual_corners",
    "refine_corners",
    "register_frame",
    "texture_transform",
]

MANUAL_CORNERS_VERSION = 1


class MarksNotFoundError(InputError):
    """No border quadrilateral was found in a frame, even at the lowest threshold tried."""


class CornerDetection(NamedTuple):
    """Result of :func:`detect_corners`."""

    corners_xy: np.ndarray  # (4, 2) coarse corners, texture order
    threshold: float  # the threshold at which the border was found
    attempts: int  # thresholds tried, 1 when the first one worked


def local_pca_lines(
    points_xy: np.ndarray, *, n_clusters: int = 6, max_iterations: int = 100
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit ``n_clusters`` lines to ordered contour points by local PCA with one component [KL97].

    Clusters start as consecutive arcs of the contour. Each round fits a line (centroid and first
    principal component) to every cluster and reassigns each point to the line with the smallest
    reconstruction error (its distance to the line). A cluster that empties, or whose line
    duplicates a larger cluster's line (within 2 degrees and 1 pixel), is re-seeded at the
    worst-fitted points, so the extra clusters end up on artifacts (rounded corners, glints)
    instead of splitting a side.

    Parameters
    ----------
    points_xy
        ``(n, 2)`` points in contour order (a closed contour without its repeated end point).
    n_clusters
        Number of clusters (lines); the thesis uses 6.
    max_iterations
        Upper bound on the rounds.

    Returns
    -------
    centres : numpy.ndarray
        ``(n_clusters, 2)`` cluster centroids.
    directions : numpy.ndarray
        ``(n_clusters, 2)`` unit principal directions.
    labels : numpy.ndarray
        ``(n,)`` cluster of each point.

    References
    ----------
    The thesis, section 4.1.2, step 4(a); [KL97].
    """
    if not (isinstance(n_clusters, (int, np.integer)) and n_clusters >= 1):
        raise InputError(f"n_clusters: expected a positive integer, got {n_clusters!r}")
    points = np.asarray(points_xy, dtype=np.float64)
    count = len(points)
    if points.ndim != 2 or points.shape[1] != 2 or count < 2 * n_clusters:
        raise InputError(
            f"points_xy: expected (n, 2) contour points with n >= {2 * n_clusters}, "
            f"got shape {points.shape}"
        )
    labels = (np.arange(count) * n_clusters) // count
    window = max(2, count // (4 * n_clusters))
    reseeds_left = 2 * n_clusters
    centres = np.zeros((n_clusters, 2))
    directions = np.tile([1.0, 0.0], (n_clusters, 1))
    for _ in range(max_iterations):
        for cluster in range(n_clusters):
            members = points[labels == cluster]
            if len(members) >= 2:
                centres[cluster] = members.mean(axis=0)
                _, vectors = np.linalg.eigh(np.cov(members.T))
                directions[cluster] = vectors[:, -1]
        normals = np.column_stack([-directions[:, 1], directions[:, 0]])
        distances = np.abs(np.einsum("nkd,kd->nk", points[:, None, :] - centres, normals))
        new_labels = np.argmin(distances, axis=1)
        sizes = np.bincount(new_labels, minlength=n_clusters)
        stale = _stale_cluster(centres, directions, normals, sizes)
        if stale is not None and reseeds_left > 0:
            reseeds_left -= 1
            worst = int(np.argmax(distances[np.arange(count), new_labels]))
            new_labels[np.arange(worst - window, worst + window + 1) % count] = stale
        elif np.array_equal(new_labels, labels):
            break
        labels = new_labels
    return centres, directions, labels


def _stale_cluster(
    centres: np.ndarray, directions: np.ndarray, normals: np.ndarray, sizes: np.ndarray
) -> int | None:
    """A cluster to re-seed: one with fewer than 2 points, or the smaller of two duplicate lines."""
    if np.any(sizes < 2):
        return int(np.argmin(sizes))
    for first in range(len(sizes)):
        for second in range(first + 1, len(sizes)):
            parallel = abs(float(directions[first] @ directions[second])) > np.cos(np.radians(2))
            offset = abs(float((centres[second] - centres[first]) @ normals[first]))
            if parallel and offset < 1.0:
                return first if sizes[first] < sizes[second] else second
    return None


def order_corners(corners_xy: np.ndarray, *, expected_xy: np.ndarray | None = None) -> np.ndarray:
    """Order four corners of a convex quadrilateral like the texture corners.

    Without ``expected_xy``: the first corner is the one nearest the image's top-left (smallest
    ``x + y``) and the corners wind so that the texture appears unmirrored (``u`` to the right,
    ``v`` downwards for a frontal view). With ``expected_xy`` (approximate corners in texture
    order, e.g. from the rig kinematics): the cyclic order and winding closest to it.

    Parameters
    ----------
    corners_xy
        ``(4, 2)`` corners in order around the quadrilateral (either winding).
    expected_xy
        Optional ``(4, 2)`` approximate corners in texture order.

    Returns
    -------
    numpy.ndarray
        ``(4, 2)`` corners in texture order.

    Examples
    --------
    >>> order_corners(np.array([[90.0, 10], [90, 90], [10, 90], [10, 10]]))
    array([[10., 10.],
           [90., 10.],
           [90., 90.],
           [10., 90.]])
    """
    corners = validate_corners(corners_xy)
    if expected_xy is not None:
        expected = validate_corners(expected_xy, "expected_xy")
        candidates = [np.roll(corners, shift, axis=0) for shift in range(4)]
        candidates += [np.roll(corners[::-1], shift, axis=0) for shift in range(4)]
        costs = [np.linalg.norm(candidate - expected, axis=1).sum() for candidate in candidates]
        return candidates[int(np.argmin(costs))]
    if _signed_area(corners) < 0:
        corners = corners[::-1]
    return np.roll(corners, -int(np.argmin(corners.sum(axis=1))), axis=0)


def _signed_area(points_xy: np.ndarray) -> float:
    """Shoelace area; positive for a clockwise turn on screen (``y`` pointing down)."""
    x, y = points_xy[:, 0], points_xy[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _line_intersection(
    centre_a: np.ndarray, direction_a: np.ndarray, centre_b: np.ndarray, direction_b: np.ndarray
) -> np.ndarray:
    steps = np.linalg.solve(np.column_stack([direction_a, -direction_b]), centre_b - centre_a)
    return centre_a + steps[0] * direction_a


def _contour_quadrilateral(
    points: np.ndarray, *, n_clusters: int, min_angle_deg: float
) -> np.ndarray | None:
    """Step 4 for one outer contour: its four corners in winding order, or None."""
    centres, directions, labels = local_pca_lines(points, n_clusters=n_clusters)
    sizes = np.bincount(labels, minlength=n_clusters)
    kept = np.argsort(sizes)[n_clusters - 4 :]  # drop the n_clusters - 4 (= 2) smallest
    extent = float(np.ptp(points, axis=0).max())
    tolerance = max(3.0, 0.1 * extent)
    corners = []
    for position, first in enumerate(kept):
        for second in kept[position + 1 :]:
            cosine = abs(float(directions[first] @ directions[second]))
            if np.degrees(np.arccos(min(cosine, 1.0))) <= min_angle_deg:
                continue
            point = _line_intersection(
                centres[first], directions[first], centres[second], directions[second]
            )
            if np.linalg.norm(points - point, axis=1).min() < tolerance:
                corners.append(point)
    if len(corners) != 4:
        return None
    found = np.array(corners)
    angles = np.arctan2(*(found - found.mean(axis=0)).T[::-1])
    return found[np.argsort(angles)]


def _adequate(
    corners: np.ndarray, contour_area: float, shape: tuple[int, int], side_px: tuple[float, float]
) -> bool:
    """Step 5: a convex quadrilateral inside the frame, sides in ``side_px``, area like its
    contour's."""
    try:
        validate_corners(corners)
    except InputError:
        return False
    sides = np.linalg.norm(np.roll(corners, -1, axis=0) - corners, axis=1)
    inside = np.all((corners >= 0) & (corners <= np.array(shape[::-1], dtype=np.float64)))
    ratio = abs(_signed_area(corners)) / max(contour_area, 1e-12)
    return bool(
        inside and side_px[0] <= sides.min() and sides.max() <= side_px[1] and 0.8 < ratio < 1.25
    )


def _positive_range(value: Any, name: str) -> tuple[float, float]:
    try:
        low, high = (float(item) for item in value)
    except (TypeError, ValueError) as error:
        raise InputError(f"{name}: expected (min, max) in pixels, got {value!r}") from error
    if not (np.isfinite(low) and np.isfinite(high) and 0 <= low < high):
        raise InputError(f"{name}: expected 0 <= min < max in pixels, got {value!r}")
    return low, high


def detect_corners(
    image: np.ndarray,
    *,
    marks: Literal["dark", "bright"] = "dark",
    threshold: float | None = None,
    threshold_step: float = 0.8,
    max_attempts: int = 10,
    contour_extent_px: tuple[float, float] | None = None,
    side_px: tuple[float, float] | None = None,
    n_clusters: int = 6,
    min_angle_deg: float = 10.0,
    expected_xy: np.ndarray | None = None,
) -> CornerDetection:
    """Coarse corners of the registration border by thresholding, contours and local PCA.

    Parameters
    ----------
    image
        Frame ``(H, W)`` or ``(H, W, K)`` (channels are averaged), linear intensities.
    marks
        ``"dark"``: the binary image holds pixels below the threshold and the outer corners of a
        dark region are found (the twin's black print); ``"bright"``: pixels above it (the
        thesis's white border).
    threshold
        First threshold, in the frame's units; default half the frame's 99th percentile.
    threshold_step
        Factor in ``(0, 1)`` by which the threshold is reduced when no quadrilateral is found
        (step 6).
    max_attempts
        Thresholds tried before giving up.
    contour_extent_px
        ``(min, max)`` adequate extent (the larger side of the bounding box) of a contour;
        default ``(max(8, 0.05 * min(H, W)), 0.95 * max(H, W))``.
    side_px
        ``(min, max)`` adequate side length of a quadrilateral; default
        ``(max(4, 0.02 * min(H, W)), max(H, W))``.
    n_clusters
        Clusters of the local PCA (the thesis: 6); the ``n_clusters - 4`` smallest are dropped.
    min_angle_deg
        Lines meeting at this angle or less are not intersected (the thesis: 10 degrees).
    expected_xy
        Optional approximate corners ``(4, 2)`` in texture order (e.g. from the rig kinematics):
        picks the quadrilateral nearest to them and orders its corners alike; a quadrilateral
        whose corners lie on average more than a tenth of the expected mean side away is not the
        border (e.g. the border cut by the frame's edge left only an inner square), and the
        search goes on. Without it the largest adequate quadrilateral is taken and ordered by
        :func:`order_corners`.

    Returns
    -------
    CornerDetection
        ``corners_xy`` (4, 2), the ``threshold`` that found them and the number of ``attempts``.

    Raises
    ------
    MarksNotFoundError
        No adequate quadrilateral at any threshold tried; give the frame's corners in a manual
        corner file.
    InputError
        Bad arguments.

    References
    ----------
    The thesis, section 4.1.2, steps 1-6; [KL97].
    """
    validate_marks(marks)
    intensity = frame_intensity(validate_frame(image))
    height, width = intensity.shape
    if threshold is None:
        threshold = 0.5 * float(np.percentile(intensity, 99))
    if not (np.isfinite(threshold) and threshold > 0):
        raise InputError(
            f"threshold: expected a positive finite value (or None), got {threshold!r}; "
            "the frame must have positive intensities"
        )
    if not 0 < threshold_step < 1:
        raise InputError(f"threshold_step: expected a factor in (0, 1), got {threshold_step}")
    if not (isinstance(max_attempts, (int, np.integer)) and max_attempts >= 1):
        raise InputError(f"max_attempts: expected an integer >= 1, got {max_attempts!r}")
    if not (isinstance(n_clusters, (int, np.integer)) and n_clusters >= 4):
        raise InputError(f"n_clusters: expected an integer >= 4, got {n_clusters!r}")
    if not 0 <= min_angle_deg < 90:
        raise InputError(f"min_angle_deg: expected [0, 90) degrees, got {min_angle_deg}")
    extent_range = _positive_range(
        contour_extent_px or (max(8.0, 0.05 * min(height, width)), 0.95 * max(height, width)),
        "contour_extent_px",
    )
    side_range = _positive_range(
        side_px or (max(4.0, 0.02 * min(height, width)), float(max(height, width))), "side_px"
    )
    expected = None if expected_xy is None else validate_corners(expected_xy, "expected_xy")
    if expected is not None:
        tolerance = 0.1 * float(
            np.linalg.norm(np.roll(expected, -1, axis=0) - expected, axis=1).mean()
        )
    level = float(threshold)
    for attempt in range(1, int(max_attempts) + 1):
        binary = intensity < level if marks == "dark" else intensity > level
        padded = np.pad(binary, 1).astype(np.float64)
        quadrilaterals = []
        for contour in measure.find_contours(padded, 0.5, positive_orientation="high"):
            if len(contour) < 4 * n_clusters or not np.allclose(contour[0], contour[-1]):
                continue
            points = contour[:-1, ::-1] - 0.5  # (row, column) of the padded image -> (x, y)
            area = _signed_area(points)
            if area >= 0:  # winds clockwise around background: a hole, not an outer contour
                continue
            if not extent_range[0] <= float(np.ptp(points, axis=0).max()) <= extent_range[1]:
                continue
            corners = _contour_quadrilateral(
                points, n_clusters=int(n_clusters), min_angle_deg=min_angle_deg
            )
            if corners is not None and _adequate(corners, -area, (height, width), side_range):
                quadrilaterals.append(corners)
        if quadrilaterals:
            if expected is not None:
                ordered = [order_corners(quad, expected_xy=expected) for quad in quadrilaterals]
                costs = [np.linalg.norm(quad - expected, axis=1).mean() for quad in ordered]
                if min(costs) <= tolerance:
                    return CornerDetection(ordered[int(np.argmin(costs))], level, attempt)
                level *= threshold_step
                continue
            largest = max(quadrilaterals, key=lambda quad: abs(_signed_area(quad)))
            return CornerDetection(order_corners(largest), level, attempt)
        level *= threshold_step
    raise MarksNotFoundError(
        f"image: no adequate border quadrilateral ({marks} marks) found at {max_attempts} "
        f"thresholds from {threshold:.6g} down to {level / threshold_step:.6g}; expected the "
        "sample holder's border in view, or give this frame's corners in a manual corner file"
    )


def extract_texture(
    image: np.ndarray, corners_xy: np.ndarray, *, resolution: int = 256, footprint: int = 1
) -> np.ndarray:
    """Texture of the sample area: every texel of ``[0, 1]^2`` mapped to the frame with
    :math:`H^{-1}` and interpolated bilinearly; with ``footprint`` above 1 each texel is the mean
    of ``footprint x footprint`` such samples spread evenly over its square, the frame averaged
    over the texel's footprint (a texel covering many pixels then takes no more of its
    neighbours than the pixels at its border hold).

    Parameters
    ----------
    image
        Frame ``(H, W)`` or multi-channel frame ``(H, W, K)`` (e.g. a band stack moved to the
        last axis).
    corners_xy
        ``(4, 2)`` corners in texture order.
    resolution
        Texels per side (the thesis: freely chosen, at most about 800 for its frontal views).
    footprint
        Samples per side of each texel's square (1: its centre only).

    Returns
    -------
    numpy.ndarray
        ``(resolution, resolution)`` or ``(resolution, resolution, K)`` float64; texel
        ``(i, j)`` is texture ``((j + 0.5) / resolution, (i + 0.5) / resolution)``. Texels that
        map outside the frame are NaN.

    References
    ----------
    The thesis, section 4.1.2 ("mapping all positions x in [0, 1]^2 in texture space to the
    respective raw image position x' and using linear interpolation").

    Examples
    --------
    >>> frame = np.tile(np.arange(8.0), (8, 1))  # value = column index
    >>> extract_texture(frame, np.array([[2.0, 2], [6, 2], [6, 6], [2, 6]]), resolution=4)[0]
    array([2., 3., 4., 5.])
    >>> edge = np.repeat([[0.0] * 8 + [1.0] * 8], 16, axis=0)  # pixels 0-7 dark, 8-15 bright
    >>> square = np.array([[3.0, 3], [11, 3], [11, 11], [3, 11]])  # texels over x 3-7, 7-11
    >>> extract_texture(edge, square, resolution=2)[0]  # the second texel's centre is bright
    array([0., 1.])
    >>> extract_texture(edge, square, resolution=2, footprint=4)[0]  # a quarter of it is dark
    array([0.  , 0.75])
    """
    array = validate_frame(image)
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise InputError(f"resolution: expected a positive integer, got {resolution!r}")
    if not (isinstance(footprint, (int, np.integer)) and footprint >= 1):
        raise InputError(f"footprint: expected a positive integer, got {footprint!r}")
    if footprint > 1:
        fine = extract_texture(array, corners_xy, resolution=resolution * footprint)
        blocks = fine.reshape(resolution, footprint, resolution, footprint, *fine.shape[2:])
        return blocks.mean(axis=(1, 3))
    to_image = texture_transform(corners_xy).inverse.params
    texel_to_texture = np.array(
        [[1 / resolution, 0, 0.5 / resolution], [0, 1 / resolution, 0.5 / resolution], [0, 0, 1]]
    )
    to_array = np.array([[1.0, 0.0, -0.5], [0.0, 1.0, -0.5], [0.0, 0.0, 1.0]])
    mapping = transform.ProjectiveTransform(matrix=to_array @ to_image @ texel_to_texture)
    return transform.warp(
        array,
        mapping,
        output_shape=(resolution, resolution),
        order=1,
        mode="constant",
        cval=np.nan,
        clip=False,
        preserve_range=True,
    )


def parse_manual_corners(document: Mapping[str, object]) -> dict[str, np.ndarray]:
    """Validate a manual corner document (the parsed JSON, see the module docstring).

    Parameters
    ----------
    document
        ``{"version": 1, "frames": {frame_id: [[x, y] x 4]}, "comment": ...}``.

    Returns
    -------
    dict
        Frame id to ``(4, 2)`` float64 corners in texture order.
    """
    if not isinstance(document, Mapping):
        raise InputError(
            f"manual corners: expected a JSON object with 'version' and 'frames', got "
            f"{type(document).__name__}"
        )
    unknown = set(document) - {"version", "frames", "comment"}
    if unknown:
        raise InputError(
            f"manual corners: unknown keys {sorted(unknown)}; expected 'version', 'frames' and "
            "optionally 'comment'"
        )
    if document.get("version") != MANUAL_CORNERS_VERSION:
        raise InputError(
            f"manual corners.version: expected {MANUAL_CORNERS_VERSION}, "
            f"got {document.get('version')!r}"
        )
    frames = document.get("frames")
    if not isinstance(frames, Mapping):
        raise InputError(
            "manual corners.frames: expected an object mapping frame ids to four [x, y] corners, "
            f"got {type(frames).__name__}"
        )
    corners = {}
    for frame_id, points in frames.items():
        if not isinstance(frame_id, str) or not frame_id:
            raise InputError(
                f"manual corners.frames: expected non-empty string frame ids, got {frame_id!r}"
            )
        corners[frame_id] = validate_corners(points, f"manual corners.frames[{frame_id!r}]")
    return corners


def read_manual_corners(path: str | Path) -> dict[str, np.ndarray]:
    """Read and validate a manual corner file (JSON, format in the module docstring).

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    dict
        Frame id to ``(4, 2)`` float64 corners in texture order.
    """
    try:
        document = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as error:
        raise InputError(f"path: cannot read manual corner file {path}: {error}") from error
    except json.JSONDecodeError as error:
        raise InputError(
            f"path: manual corner file {path} is not valid JSON ({error}); expected the format "
            "in recon.registration.border's docstring"
        ) from error
    return parse_manual_corners(document)


def register_frame(
    image: np.ndarray,
    *,
    frame_id: str | None = None,
    manual_corners: Mapping[str, np.ndarray] | None = None,
    marks: Literal["dark", "bright"] = "dark",
    expected_xy: np.ndarray | None = None,
    threshold: float | None = None,
    piece_texels: int = 64,
    iterations: int = 2,
) -> np.ndarray:
    """Sub-pixel corners of one frame: manual corners where given, else detection + refinement.

    Parameters
    ----------
    image
        Frame ``(H, W)`` or ``(H, W, K)``.
    frame_id
        The frame's id in ``manual_corners``.
    manual_corners
        From :func:`read_manual_corners`; a frame listed there is not detected.
    marks, expected_xy, threshold
        As in :func:`detect_corners`.
    piece_texels, iterations
        As in :func:`recon.registration.corners.refine_corners`.

    Returns
    -------
    numpy.ndarray
        ``(4, 2)`` corners ``(x, y)`` in texture order, ready for :func:`extract_texture`.

    Raises
    ------
    MarksNotFoundError
        The frame is not in ``manual_corners`` and its border was not detected.

    References
    ----------
    The thesis, section 4.1.2.
    """
    validate_marks(marks)
    array = validate_frame(image)
    if manual_corners is not None and frame_id is not None and frame_id in manual_corners:
        corners = validate_corners(manual_corners[frame_id], f"manual_corners[{frame_id!r}]")
        height, width = array.shape[:2]
        if np.any(corners < 0) or np.any(corners > np.array([width, height])):
            raise InputError(
                f"manual_corners[{frame_id!r}]: expected corners inside the {width} x {height} "
                f"frame, got {corners.tolist()}"
            )
        return corners
    detection = detect_corners(array, marks=marks, threshold=threshold, expected_xy=expected_xy)
    return refine_corners(
        array, detection.corners_xy, marks=marks, piece_texels=piece_texels, iterations=iterations
    )
