"""Homography to texture space and sub-pixel refinement of the registration corners (thesis 4.1.2).

The four corners of the registration border map to the corners of the texture square
:math:`[0, 1]^2` through a homography :math:`H`. The coarse corners of the detection are refined
the way the thesis describes: small image pieces of 0.1 x 0.1 texture units centred at the corners
are extracted in texture space (rectified by the current :math:`H`, bilinear interpolation), their
pixel values are re-mapped linearly so that the 5 and 95 percentiles become black and white
(clamped), and a Chan-Vese model [CV01] whose contour is a rectangle corner is fitted: the region
on the border's side of the corner has one constant value, the rest the other, and only the corner
point is optimized. The corner in texture space is mapped back to the image with :math:`H^{-1}`.

The thesis scans the corner position brute-force on a GPU; here a vectorized grid scan (the
nodes and errors of ``scipy.optimize.brute``) finds the best node, which Nelder-Mead polishes. The
model is rendered with partial-area texels (each texel holds the fraction of its area on the
inside of the corner), so the squared error is continuous in the corner position and the corner
is found to a fraction of a texel.

Departure from the thesis (``edge_model="blurred"``, the default): the model's two edges are
blurred by a Gaussian whose widths (along ``u`` and ``v``) are fitted with the corner. With sharp
edges the fit is pulled towards the inside by the rounded, blurred image corner by about
``blur^2 / piece extent``: negligible for the thesis's frames, where a 0.1-unit piece spans about
80 pixels, but 0.05-0.2 px for the twin's 256-pixel frames, where it spans about 7 pixels.
``edge_model="sharp"`` is the thesis's model. The intensities stay fixed at 0 and 1 as in the
thesis.

Conventions
-----------
- Image points are ``(x, y)`` = (column, row) in continuous pixel coordinates with pixel centres at
  ``+0.5`` (as ``twin.render.scene.PinholeCamera.project``): pixel ``(r, c)`` covers
  ``[c, c + 1) x [r, r + 1)``.
- Corners are ordered like :data:`TEXTURE_CORNERS_UV`: the i-th image corner maps to the i-th
  texture corner ``(u, v)``; ``u`` runs along texture columns, ``v`` along texture rows.

References
----------
- The thesis, section 4.1.2 "Post-Processing" and Figure 4.1(d).
- [CV01] Chan, T. F., & Vese, L. A. (2001). Active contours without edges. IEEE Transactions on
  Image Processing, 10(2), 266-277. doi:10.1109/83.902291
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from scipy import optimize, special
from skimage import transform

from recon.errors import InputError

__all__ = [
    "CORNER_PIECE_SIZE",
    "TEXTURE_CORNERS_UV",
    "corner_pieces",
    "fit_corner_model",
    "frame_intensity",
    "refine_corners",
    "shifted_corners",
    "texture_transform",
    "validate_corners",
    "validate_frame",
    "validate_marks",
]

CORNER_PIECE_SIZE = 0.1
"""Width and height in texture units of the image piece each corner is refined in (thesis
4.1.2); half of it lies outside the border, where the contrast comes from."""

TEXTURE_CORNERS_UV = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
"""Texture-space positions of corners 0..3: ``(u, v)``; the border lies inside the unit square."""
TEXTURE_CORNERS_UV.setflags(write=False)

MARKS = ("dark", "bright")


class CornerRefinementError(InputError):
    """The two-region model put a corner at the edge of its piece: no border corner was found
    near the coarse corner (too few pixels across the border, e.g. at grazing views)."""


def validate_corners(corners_xy: object, name: str = "corners_xy") -> np.ndarray:
    """``corners_xy`` as a float64 ``(4, 2)`` array of a convex, non-degenerate quadrilateral.

    Parameters
    ----------
    corners_xy
        Four image points ``(x, y)``, consecutive corners sharing a side.
    name
        Name of the argument in error messages.

    Returns
    -------
    numpy.ndarray
        ``(4, 2)`` float64 copy.

    Raises
    ------
    InputError
        Wrong shape, non-finite values, or four points that are not the corners of a convex
        quadrilateral in order (self-intersecting, collinear or repeated points).
    """
    try:
        corners = np.array(corners_xy, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(
            f"{name}: expected four (x, y) points as numbers, got {corners_xy!r}"
        ) from error
    if corners.shape != (4, 2):
        raise InputError(
            f"{name}: expected shape (4, 2) (four (x, y) corners), got {corners.shape}"
        )
    if not np.all(np.isfinite(corners)):
        raise InputError(f"{name}: expected finite corner coordinates, got {corners}")
    edges = np.roll(corners, -1, axis=0) - corners
    turns = (
        edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, 0)[:, 0]
    )
    scale = max(float(np.abs(edges).max()), 1e-300) ** 2
    if not (np.all(turns > 1e-9 * scale) or np.all(turns < -1e-9 * scale)):
        raise InputError(
            f"{name}: expected the corners of a convex quadrilateral in order around it "
            f"(no repeated, collinear or crossing corners), got {corners.tolist()}"
        )
    return corners


def texture_transform(corners_xy: np.ndarray) -> transform.ProjectiveTransform:
    """Homography :math:`H` from image points ``(x, y)`` to texture space ``(u, v)``.

    Parameters
    ----------
    corners_xy
        ``(4, 2)`` image corners ordered like :data:`TEXTURE_CORNERS_UV`.

    Returns
    -------
    skimage.transform.ProjectiveTransform
        ``H(points_xy) -> points_uv``; ``H.inverse`` maps texture points back to the image.

    References
    ----------
    The thesis, section 4.1.2 ("a homography matrix ... maps the plane of the border in image space
    to the proxy/texture plane of the material").

    Examples
    --------
    >>> h = texture_transform(np.array([[10.0, 10], [50, 12], [48, 52], [9, 49]]))
    >>> np.round(h(np.array([[50.0, 12.0]])), 6) + 0.0  # + 0.0: the sign of a rounded zero
    array([[1., 0.]])
    """
    corners = validate_corners(corners_xy)
    estimated = transform.ProjectiveTransform.from_estimate(corners, TEXTURE_CORNERS_UV)
    if not estimated:
        raise InputError(
            f"corners_xy: no homography to the texture square exists for {corners.tolist()}"
        )
    return estimated


def shifted_corners(corners_xy: np.ndarray, shift_texels: np.ndarray, texels: int) -> np.ndarray:
    """The image corners of the sample square whose texture at ``texels`` per side is the
    texture of ``corners_xy`` moved by ``shift_texels`` ``(rows, columns)``, as
    :func:`scipy.ndimage.shift` moves an array: texel ``(i, j)`` of the new texture is the point
    ``(i - rows, j - columns)`` of the old one. Rectifying a frame at these corners gives that
    texture with one resampling instead of two.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [8, 0], [8, 8], [0, 8]])  # 8 x 8 pixels, 4 texels a side
    >>> np.round(shifted_corners(square, np.array([0.0, 1.0]), 4), 6) + 0.0  # one texel right
    array([[-2.,  0.],
           [ 6.,  0.],
           [ 6.,  8.],
           [-2.,  8.]])
    """
    uv = TEXTURE_CORNERS_UV - np.asarray(shift_texels, np.float64)[::-1] / texels
    return np.asarray(texture_transform(corners_xy).inverse(uv))


def validate_frame(image: object, name: str = "image") -> np.ndarray:
    """``image`` as a float64 frame ``(H, W)`` or ``(H, W, K)`` of finite values, at least 8 x 8.

    Raises
    ------
    InputError
        Not numeric, wrong number of axes, too small, NaN or inf.
    """
    try:
        array = np.asarray(image, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"{name}: expected a numeric array, got {type(image)}") from error
    if array.ndim not in (2, 3) or min(array.shape[:2]) < 8 or array.size == 0:
        raise InputError(
            f"{name}: expected a frame (H, W) or (H, W, K) of at least 8 x 8 pixels, "
            f"got shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name}: expected finite pixel values, found NaN or inf")
    return array


def frame_intensity(image: np.ndarray) -> np.ndarray:
    """Single-channel intensity of a validated frame: itself, or the mean over its last axis."""
    return image if image.ndim == 2 else image.mean(axis=-1)


def validate_marks(marks: str) -> None:
    """Raise :class:`InputError` unless ``marks`` is ``"dark"`` or ``"bright"``."""
    if marks not in MARKS:
        raise InputError(f"marks: expected one of {MARKS}, got {marks!r}")


def corner_pieces(
    image: np.ndarray,
    corners_xy: np.ndarray,
    *,
    piece_size: float = CORNER_PIECE_SIZE,
    piece_texels: int = 64,
    percentiles: tuple[float, float] = (5.0, 95.0),
) -> np.ndarray:
    """The four normalized texture-space image pieces centred at the corners (Figure 4.1(d)).

    Parameters
    ----------
    image
        Frame ``(H, W)`` or ``(H, W, K)`` (channels are averaged).
    corners_xy
        ``(4, 2)`` current corner estimates, ordered like :data:`TEXTURE_CORNERS_UV`.
    piece_size
        Width and height of a piece in texture units (the thesis: 0.1).
    piece_texels
        Resolution of a piece (texels per side; the thesis: "can be freely chosen").
    percentiles
        Values mapped to 0 and 1 (the thesis: 5 and 95); the result is clamped to ``[0, 1]``.

    Returns
    -------
    numpy.ndarray
        ``(4, piece_texels, piece_texels)``; texel ``(i, j)`` of piece ``k`` lies at texture
        ``TEXTURE_CORNERS_UV[k] + (piece_size * ((j + 0.5) / n - 0.5),
        piece_size * ((i + 0.5) / n - 0.5))``.
    """
    intensity = frame_intensity(validate_frame(image))
    corners = validate_corners(corners_xy)
    _validate_piece_options(piece_size, piece_texels, percentiles)
    to_image = texture_transform(corners).inverse.params
    step = piece_size / piece_texels
    pieces = np.empty((4, piece_texels, piece_texels))
    for index, (u, v) in enumerate(TEXTURE_CORNERS_UV):
        # piece texel (column j, row i) -> texture (u, v) -> image (x, y) -> array (x-.5, y-.5)
        to_texture = np.array(
            [
                [step, 0.0, u - piece_size / 2 + step / 2],
                [0.0, step, v - piece_size / 2 + step / 2],
                [0.0, 0.0, 1.0],
            ]
        )
        to_array = np.array([[1.0, 0.0, -0.5], [0.0, 1.0, -0.5], [0.0, 0.0, 1.0]])
        mapping = transform.ProjectiveTransform(matrix=to_array @ to_image @ to_texture)
        piece = transform.warp(
            intensity,
            mapping,
            output_shape=(piece_texels, piece_texels),
            order=1,
            mode="edge",
            clip=False,
            preserve_range=True,
        )
        low, high = np.percentile(piece, percentiles)
        if not high > low:
            raise InputError(
                f"image: the piece around corner {index} at {np.round(corners[index], 2)} has no "
                f"contrast between its {percentiles} percentiles; expected the border's edges there"
            )
        pieces[index] = np.clip((piece - low) / (high - low), 0.0, 1.0)
    return pieces


def _validate_piece_options(
    piece_size: float, piece_texels: int, percentiles: tuple[float, float]
) -> None:
    if not (np.isfinite(piece_size) and 0.0 < piece_size <= 0.5):
        raise InputError(
            f"piece_size: expected a width in texture units in (0, 0.5], got {piece_size!r}"
        )
    if not (isinstance(piece_texels, (int, np.integer)) and piece_texels >= 8):
        raise InputError(f"piece_texels: expected an integer of at least 8, got {piece_texels!r}")
    low, high = (float(value) for value in percentiles)
    if not 0.0 <= low < high <= 100.0:
        raise InputError(
            f"percentiles: expected (low, high) with 0 <= low < high <= 100, got {percentiles!r}"
        )


def _coverage(centres: np.ndarray, edge: float, sign: float, width: float | None) -> np.ndarray:
    """Share of each texel (centres given) on the side ``sign * (t - edge) > 0`` of an edge.

    ``width`` None: the sharp edge's area fraction of unit texels; else a Gaussian-blurred edge of
    standard deviation ``width`` texels."""
    if width is None:
        return np.clip(sign * (centres - edge) + 0.5, 0.0, 1.0)
    with np.errstate(divide="ignore", over="ignore"):  # width 0: the sharp edge's step
        return special.ndtr(sign * (centres - edge) / width)


def _corner_errors(
    values: np.ndarray,
    across: np.ndarray,
    down: np.ndarray,
    outside_value: float,
    contrast: float,
) -> np.ndarray:
    """Squared error of :func:`fit_corner_model`'s model against the piece ``values`` ``(n, n)``
    for the columns' coverages ``across`` ``(..., n)`` and the rows' ``down`` ``(..., n)``
    (broadcast against each other: one error per corner)."""
    model = outside_value + contrast * (down[..., :, None] * across[..., None, :])
    return np.sum((values - model) ** 2, axis=(-2, -1))


def _grid_scan(
    values: np.ndarray,
    inside: tuple[int, int],
    widths: tuple[float | None, float | None],
    outside_value: float,
    contrast: float,
    grid_points: int,
) -> np.ndarray:
    """The corner of ``grid_points`` x ``grid_points`` nodes over the piece with the least squared
    error of :func:`fit_corner_model`'s model: ``scipy.optimize.brute`` over the same nodes
    (``finish=None``), the same error at every node to the bit, one row of nodes at a time
    instead of one Python call per node."""
    size = values.shape[0]
    centres = np.arange(size) + 0.5
    span = slice(0.5, size - 0.5, complex(grid_points))
    grid = np.mgrid[span, span]
    across = _coverage(centres[None, :], grid[0][:, :1], inside[0], widths[0])
    down = _coverage(centres[None, :], grid[1][:1, :].T, inside[1], widths[1])
    errors = np.stack(
        [_corner_errors(values, row[None, :], down, outside_value, contrast) for row in across]
    )
    best = np.unravel_index(np.argmin(errors), errors.shape)
    return np.array([grid[0][best], grid[1][best]])


def fit_corner_model(
    piece: np.ndarray,
    *,
    inside: tuple[int, int],
    inside_value: float = 1.0,
    outside_value: float = 0.0,
    edge_width: tuple[float, float] | None = None,
    fit_edge_width: bool = False,
    grid_points: int = 25,
) -> np.ndarray:
    """Corner of a rectangular two-region Chan-Vese model fitted to one normalized piece.

    The model has ``inside_value`` on the quadrant ``inside`` of the corner ``(a, b)`` and
    ``outside_value`` elsewhere, the contour being the corner's two edges along the piece's axes.
    With sharp edges (the thesis's model) each texel takes the two values in proportion to its area
    on either side; with ``edge_width`` the edges are blurred by a Gaussian of that standard
    deviation (along ``u``, ``v``) - the image's pixel footprint seen in texture space - which
    removes the pull of the blurred, rounded image corner towards the inside when a piece spans
    only a few image pixels. The corner (and, with ``fit_edge_width``, the widths) minimizing the
    squared error is found by a brute-force grid scan of the corner (as ``scipy.optimize.brute``,
    vectorized) polished by Nelder-Mead.

    Parameters
    ----------
    piece
        ``(n, n)`` normalized piece (values in ``[0, 1]``).
    inside
        ``(sign_u, sign_v)``, each +1 or -1: the inside quadrant is where
        ``sign_u * (column - a) > 0`` and ``sign_v * (row - b) > 0``.
    inside_value, outside_value
        The two constants (the thesis: inside 1, outside 0).
    edge_width
        ``(sigma_u, sigma_v)`` in texels, or None for sharp edges; the start value when fitted.
    fit_edge_width
        Optimize the edge widths along with the corner (needs ``edge_width``).
    grid_points
        Nodes per axis of the brute-force scan over the piece.

    Returns
    -------
    numpy.ndarray
        ``(a, b)`` in texel units of the piece: column then row, texel ``j`` spanning ``[j, j+1)``.

    References
    ----------
    The thesis, section 4.1.2; [CV01].

    Examples
    --------
    >>> piece = np.zeros((16, 16)); piece[6:, 9:] = 1.0
    >>> np.round(fit_corner_model(piece, inside=(1, 1)), 3)
    array([9., 6.])
    """
    values = np.asarray(piece, dtype=np.float64)
    if values.ndim != 2 or values.shape[0] != values.shape[1] or values.shape[0] < 4:
        raise InputError(f"piece: expected a square (n, n) array, got {values.shape}")
    if tuple(inside) not in {(1, 1), (1, -1), (-1, 1), (-1, -1)}:
        raise InputError(f"inside: expected (+-1, +-1), got {inside!r}")
    widths = None
    if edge_width is not None:
        widths = np.asarray(edge_width, dtype=np.float64)
        if widths.shape != (2,) or not np.all(np.isfinite(widths) & (widths > 0)):
            raise InputError(
                f"edge_width: expected two positive widths in texels, got {edge_width!r}"
            )
    elif fit_edge_width:
        raise InputError("edge_width: expected start widths when fit_edge_width is set")
    size = values.shape[0]
    centres = np.arange(size) + 0.5
    contrast = inside_value - outside_value

    def squared_error(corner: np.ndarray, width_u: float | None, width_v: float | None) -> float:
        across = _coverage(centres, corner[0], inside[0], width_u)
        down = _coverage(centres, corner[1], inside[1], width_v)
        return float(_corner_errors(values, across, down, outside_value, contrast))

    fixed = (None, None) if widths is None else (float(widths[0]), float(widths[1]))
    found = _grid_scan(values, inside, fixed, outside_value, contrast, grid_points)
    if fit_edge_width and widths is not None:
        start = np.concatenate([found, np.log(widths)])
        polished = optimize.minimize(
            lambda p: squared_error(p[:2], *np.exp(p[2:])),
            start,
            method="Nelder-Mead",
            options={"xatol": 1e-4, "fatol": 1e-12, "maxiter": 2000},
        ).x[:2]
    else:
        polished = optimize.minimize(
            squared_error,
            found,
            args=fixed,
            method="Nelder-Mead",
            options={"xatol": 1e-4, "fatol": 1e-12},
        ).x
    return np.clip(np.asarray(polished, dtype=np.float64), 0.0, float(size))


def refine_corners(
    image: np.ndarray,
    corners_xy: np.ndarray,
    *,
    marks: Literal["dark", "bright"] = "dark",
    piece_size: float = CORNER_PIECE_SIZE,
    piece_texels: int = 64,
    percentiles: tuple[float, float] = (5.0, 95.0),
    iterations: int = 2,
    edge_model: Literal["blurred", "sharp"] = "blurred",
) -> np.ndarray:
    """Sub-pixel corners: texture-space pieces, percentile normalization, Chan-Vese corner fit.

    Parameters
    ----------
    image
        Frame ``(H, W)`` or ``(H, W, K)`` (channels are averaged).
    corners_xy
        ``(4, 2)`` coarse corners ``(x, y)``, ordered like :data:`TEXTURE_CORNERS_UV`.
    marks
        ``"dark"``: the border region inside each corner is darker than its surroundings (the
        outer corners of a black print on white paper, as on the twin's sample holder);
        ``"bright"``: it is brighter (the thesis's white border, whose inside is 1).
    piece_size, piece_texels, percentiles
        As in :func:`corner_pieces`.
    iterations
        Rounds of refinement; each re-estimates :math:`H` from the previous round's corners, so
        that the pieces are rectified by an ever better homography.
    edge_model
        ``"sharp"``: the thesis's model, sharp edges. ``"blurred"``: edges blurred by a Gaussian
        whose widths start at half an image pixel seen in texture space and are fitted with the
        corner (see :func:`fit_corner_model`); unbiased when a piece spans only a few pixels.

    Returns
    -------
    numpy.ndarray
        ``(4, 2)`` refined corners ``(x, y)`` in the order given.

    Raises
    ------
    InputError
        Bad arguments, or a corner that moves out of its piece (no corner edge was found there).

    References
    ----------
    The thesis, section 4.1.2; [CV01].
    """
    validate_marks(marks)
    if not (isinstance(iterations, (int, np.integer)) and iterations >= 1):
        raise InputError(f"iterations: expected an integer >= 1, got {iterations!r}")
    image = validate_frame(image)
    corners = validate_corners(corners_xy)
    if edge_model not in ("blurred", "sharp"):
        raise InputError(f"edge_model: expected 'blurred' or 'sharp', got {edge_model!r}")
    inside_value, outside_value = (1.0, 0.0) if marks == "bright" else (0.0, 1.0)
    step = piece_size / piece_texels
    for _ in range(int(iterations)):
        pieces = corner_pieces(
            image,
            corners,
            piece_size=piece_size,
            piece_texels=piece_texels,
            percentiles=percentiles,
        )
        to_texture = texture_transform(corners)
        refined_uv = np.empty((4, 2))
        for index, (u, v) in enumerate(TEXTURE_CORNERS_UV):
            inside = (1 if u < 0.5 else -1, 1 if v < 0.5 else -1)  # towards the square's centre
            width = None
            if edge_model == "blurred":  # half a pixel, in texels along u and v
                steps = to_texture(corners[index] + np.array([[0, 0], [1, 0], [0, 1]]))
                jacobian = (steps[1:] - steps[0]).T  # rows: u, v; columns: per x, per y pixel
                width = tuple(0.5 * np.linalg.norm(jacobian, axis=1) / step)
            corner = fit_corner_model(
                pieces[index],
                inside=inside,
                inside_value=inside_value,
                outside_value=outside_value,
                edge_width=width,
                fit_edge_width=width is not None,
            )
            if np.any(corner <= 0.5) or np.any(corner >= piece_texels - 0.5):
                raise CornerRefinementError(
                    f"corners_xy: corner {index} at {np.round(corners[index], 2)} refined to the "
                    "edge of its piece; expected the border's corner within "
                    f"{piece_size / 2} texture units of the coarse corner"
                )
            refined_uv[index] = np.array([u, v]) - piece_size / 2 + corner * step
        corners = validate_corners(to_texture.inverse(refined_uv), "refined corners")
    return corners
