"""An appearance space learned from the known spectra: every pixel's predicted spectrum.

The appearance prior (thesis Eq. 6.3) links pixels that look alike. RGB alone (Eq. 6.4, 6.5)
cannot tell metamers apart, and a pixel's own three values say nothing of the structure around
it, which the thesis names as the way forward (section 11.2: richer appearance descriptors, e.g.
texture features around a pixel). Here every pixel is described by patch features (its camera
values, and their Gaussian local means and gradient magnitudes at several scales), and a linear
map from those features to the leading principal components of the known spectra is fitted by
ridge regression at the known pixels only (its penalty by generalized cross-validation). The
appearance point of a pixel is its predicted coefficients (and its scaled position, as in
Eq. 6.5): pixels are neighbours where their predicted spectra are close, whatever their RGB.
Because the map is fitted on the known spectra, a cross-validation that holds spots out must
refit it without them (:func:`recon.spectralize.choose_prior` does).

References
----------
- The thesis, Eq. 6.3-6.6 and section 11.2.
- Hoerl, A. E., & Kennard, R. W. (1970). Ridge regression: biased estimation for nonorthogonal
  problems. Technometrics 12(1), 55-67.
- Golub, G. H., Heath, M., & Wahba, G. (1979). Generalized cross-validation as a method for
  choosing a good ridge parameter. Technometrics 21(2), 215-223.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import ndimage

from recon.errors import InputError

__all__ = [
    "LEARNED_SPACES",
    "fitted_on",
    "learned_points",
    "patch_features",
    "standardized_features",
]

LEARNED_SPACES = frozenset({"learned"})
"""Appearance spaces whose points depend on the known spectra (options ``known_pixels`` and
``known_spectra``)."""
SCALES_PX = (1.0, 2.0, 4.0)
"""Standard deviations of the Gaussian local means and gradients, pixels."""
COMPONENTS = 6
"""Principal components of the known spectra predicted per pixel (fewer where the known spectra
span fewer dimensions)."""
RIDGE_PENALTIES = np.geomspace(1e-8, 1e2, 21)
"""Ridge penalties per known pixel tried; the one of least generalized cross-validation error
is used."""
_RANK_TOLERANCE = 1e-9  # singular values below this share of the largest span no component


def patch_features(images: np.ndarray, scales_px: Sequence[float] = SCALES_PX) -> np.ndarray:
    """Per pixel, its camera values and, per scale, their Gaussian local mean and gradient
    magnitude (reflected borders).

    Parameters
    ----------
    images
        ``(n_images, height, width, channels)`` camera values.
    scales_px
        Standard deviations of the Gaussians, pixels.

    Returns
    -------
    numpy.ndarray
        ``(n_images * height * width, channels * (1 + 2 * len(scales_px)))``.

    Examples
    --------
    >>> import numpy as np
    >>> patch_features(np.ones((1, 4, 5, 3))).shape
    (20, 21)
    """
    images = np.asarray(images, dtype=np.float64)
    channels = images.shape[-1]
    parts = [images]
    for sigma in scales_px:
        blur = (0.0, sigma, sigma, 0.0)
        parts.append(ndimage.gaussian_filter(images, blur, mode="reflect"))
        along_rows = ndimage.gaussian_filter(images, blur, order=(0, 1, 0, 0), mode="reflect")
        along_cols = ndimage.gaussian_filter(images, blur, order=(0, 0, 1, 0), mode="reflect")
        parts.append(np.hypot(along_rows, along_cols))
    return np.concatenate(parts, axis=-1).reshape(-1, channels * len(parts))


def _ridge_fit(design: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """``(features, targets)`` ridge regression of ``targets`` on ``design``, its penalty chosen
    from :data:`RIDGE_PENALTIES` by generalized cross-validation (Golub, Heath & Wahba 1979:
    the leave-one-out error of a linear smoother, in closed form from one SVD)."""
    left, singular, right = np.linalg.svd(design, full_matrices=False)
    projected = left.T @ targets
    outside = float(np.sum(targets**2) - np.sum(projected**2))  # beyond the design's span
    count = design.shape[0]
    best = (np.inf, RIDGE_PENALTIES[0])
    for penalty in RIDGE_PENALTIES * count:
        kept = singular**2 / (singular**2 + penalty)
        residual = outside + float(np.sum(((1 - kept)[:, None] * projected) ** 2))
        score = residual / max(count - kept.sum(), 1e-12) ** 2
        best = min(best, (score, penalty))
    shrink = singular / (singular**2 + best[1])
    return np.asarray(right.T @ (shrink[:, None] * projected))


def standardized_features(images: np.ndarray) -> np.ndarray:
    """:func:`patch_features` of ``images``, each column shifted and scaled to zero mean and
    unit standard deviation over the pixels (so that the ridge penalty weighs them alike), as
    float32: the ``features`` option of :func:`learned_points`, found once per image."""
    features = patch_features(images)
    features -= features.mean(axis=0)
    features /= features.std(axis=0) + 1e-12
    return features.astype(np.float32)


def learned_points(
    images: np.ndarray,
    *,
    known_pixels: np.ndarray | None = None,
    known_spectra: np.ndarray | None = None,
    features: np.ndarray | None = None,
    xy_scale: float = 0.25,
    **_: object,
) -> np.ndarray:
    """The learned appearance points (module description): predicted principal-component
    coefficients of every pixel's spectrum, then its position scaled as in Eq. 6.5.

    Parameters
    ----------
    images
        ``(n_images, height, width, channels)`` camera values.
    known_pixels, known_spectra
        Flat pixel indices and their ``(m, K)`` spectra: where the map is fitted.
    features
        :func:`standardized_features` of ``images`` where already found (several fits on one
        image); found here if not given.
    xy_scale
        Position weight: coordinates scaled to ``xy_scale`` times the mean spread of the first
        three predicted coefficients per image side (as RGBXY scales them to the RGB spread).

    Returns
    -------
    numpy.ndarray
        ``(n_images * height * width, components + 2)`` points.
    """
    if known_pixels is None or known_spectra is None:
        raise InputError(
            "appearance 'learned': expected the known spectra it is fitted on "
            "(appearance_options known_pixels and known_spectra)"
        )
    pixels = np.asarray(known_pixels)
    spectra = np.asarray(known_spectra, dtype=np.float64)
    if pixels.ndim != 1 or spectra.ndim != 2 or spectra.shape[0] != pixels.size or pixels.size < 2:
        raise InputError(
            f"known_pixels, known_spectra: expected m >= 2 indices and (m, K) spectra, got "
            f"shapes {pixels.shape} and {spectra.shape}"
        )
    count, height, width, _ = images.shape
    if features is None:
        features = standardized_features(images)
    centred = spectra - spectra.mean(axis=0)
    singular, directions = np.linalg.svd(centred, full_matrices=False)[1:]
    rank = int(np.sum(singular > _RANK_TOLERANCE * singular[0])) if singular[0] > 0 else 1
    directions = directions[: min(COMPONENTS, rank)]
    at_known = np.column_stack([features[pixels], np.ones(pixels.size)])
    projection = _ridge_fit(at_known, centred @ directions.T)
    predicted = features @ projection[:-1].astype(np.float32) + projection[-1].astype(np.float32)
    spread = float(np.mean(np.std(predicted[:, :3], axis=0))) or 1.0
    rows, cols = np.mgrid[0:height, 0:width]
    xy = np.stack([cols, rows], axis=-1).reshape(-1, 2) * (xy_scale * spread / max(height, width))
    return np.concatenate([predicted, np.tile(xy, (count, 1))], axis=1)


def fitted_on(options: dict[str, Any], pixels: np.ndarray, spectra: np.ndarray) -> dict[str, Any]:
    """Energy ``options`` with the appearance space fitted on the known ``pixels`` and their
    ``spectra`` (its ``appearance_options`` ``known_pixels`` and ``known_spectra``; any others,
    such as ``features``, kept)."""
    fitted = {"known_pixels": pixels, "known_spectra": spectra}
    return options | {"appearance_options": (options.get("appearance_options") or {}) | fitted}
