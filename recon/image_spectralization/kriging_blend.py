"""Spectralization blended with Murakami's kriged estimate, by the weight held-out spots choose.

Where the image is a smooth field in space (blends, gradients of pigment), Murakami et al.'s
estimate (:func:`recon.baselines.murakami`: a Wiener estimate plus the known spectra's
metameric-black residuals interpolated by simple kriging) spreads a one-pixel spot's
information over its neighbourhood, which the appearance graph of Eq. 6.3 does poorly
(BENCHMARKS.md, "Spectralization on real spectra"); where it is a mosaic of materials,
spectralization is several times better. Their convex combination
:math:`X = (1 - w)\\,X_{spec} + w\\,X_{krig}` (stacked regression: Breiman 1996) takes the
best of both when the kriging weight ``w`` is chosen from data neither estimate saw: the spots
held out by the folds of :func:`recon.spectralize.choose_prior`. Murakami's estimate is
computed fold by fold from the same spots as the spectralization's held-out predictions, at
the held-out spots only, so the choice costs ``folds`` kriging solves of ``m x m`` and no
image-sized work; the image's own kriged estimate is computed only where ``w > 0``, its
correction on a grid of a tenth of the correlation length (:data:`GRID_PER_LENGTH`)
interpolated bilinearly.

References
----------
- Murakami, Y., Ietomi, K., Yamaguchi, M., & Ohyama, N. (2007). Maximum a posteriori
  estimation of spectral reflectance from color image and multipoint spectral measurements.
  Applied Optics, 46(28), 7068-7082.
- Breiman, L. (1996). Stacked regressions. Machine Learning, 24(1), 49-64.
- The thesis, Eq. 6.3, 6.8 and 6.10; Sec. 7.1 (Murakami 2007 among the peers).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recon import baselines
from recon.baselines.murakami2007 import default_correlation_length
from recon.errors import InputError
from recon.metrics import relative_error
from recon.spectralize.prior_choice import PriorChoice

__all__ = [
    "GRID_PER_LENGTH",
    "KrigingWeight",
    "blend_with_kriging",
    "choose_kriging_weight",
    "kriged_estimate",
]

WEIGHTS = np.linspace(0.0, 1.0, 21)
"""The kriging weights tried, in steps of 0.05."""
GRID_PER_LENGTH = 10
"""Points of the kriging grid per correlation length for the image's own estimate (its mean
relative difference from the estimate at every pixel: 3e-5 at 192 px, grid step 2)."""


@dataclass(frozen=True)
class KrigingWeight:
    """The weight ``kriging_weight`` of the kriged estimate (``1 -`` it of the
    spectralization) and the mean held-out error (Eq. 6.8, %) of the spectralization, the
    kriged estimate and the blend; ``pixel_errors``: the blend's held-out error of every
    known pixel."""

    kriging_weight: float
    held_out_errors: dict[str, float]
    pixel_errors: np.ndarray


def _kriged(
    rgb: np.ndarray,
    response: np.ndarray,
    pixels: np.ndarray,
    spectra: np.ndarray,
    **options: object,
) -> np.ndarray:
    return baselines.recover(
        rgb, response, method="murakami", known_pixels=pixels, known_spectra=spectra, **options
    )


def choose_kriging_weight(
    rgb: np.ndarray,
    response: np.ndarray,
    known_pixels: np.ndarray,
    known_spectra: np.ndarray,
    choice: PriorChoice,
    *,
    correlation_length: float | None = None,
) -> KrigingWeight:
    """Choose the blend's weight from the spots held out by ``choice``'s folds.

    Parameters
    ----------
    rgb, response
        ``(H, W, C)`` camera values and the ``(K, C)`` response, as given to
        :func:`recon.spectralize.choose_prior`.
    known_pixels, known_spectra
        The spots' flat pixel indices and ``(m, K)`` spectra, as given to it.
    choice
        Its result: the folds, and the chosen prior's held-out predictions.
    correlation_length
        Of the kriged estimate, pixels; by default that of ``rgb``'s size
        (:func:`recon.baselines.murakami2007.default_correlation_length`). A window of a
        larger image passes the image's, which its solve from all spots uses.

    Returns
    -------
    KrigingWeight
        The kriging weight with the smallest mean held-out error (the smallest among
        equals: the spectralization alone where the kriged estimate adds nothing).

    Examples
    --------
    >>> import numpy as np
    >>> from recon.spectralize import choose_prior
    >>> rng = np.random.default_rng(1)
    >>> y, x = np.mgrid[0:24, 0:24] / 24
    >>> basis = rng.random((3, 12))
    >>> truth = np.stack([np.sin(3 * x), np.cos(2 * y), x * y], -1) @ basis + 0.1
    >>> response = rng.random((12, 3))
    >>> pixels = np.arange(0, 576, 23)
    >>> rgb, spectra = truth @ response, truth.reshape(-1, 12)[pixels]
    >>> choice = choose_prior(rgb, response, pixels, spectra)
    >>> chosen = choose_kriging_weight(rgb, response, pixels, spectra, choice)
    >>> 0.0 <= chosen.kriging_weight <= 1.0
    True
    """
    images = np.asarray(rgb, dtype=np.float64)
    if images.ndim != 3:
        raise InputError(
            f"rgb: the kriged estimate needs one (H, W, C) image, got shape {images.shape}"
        )
    pixels = np.asarray(known_pixels)
    spectra = np.asarray(known_spectra, dtype=np.float64)
    spectralized = choice.held_out_spectra[choice.prior]
    if spectralized.shape != spectra.shape:
        raise InputError(
            f"choice: expected held-out spectra of the {spectra.shape} known spectra, got "
            f"{spectralized.shape} (a choice made with other spots)"
        )
    kriged = np.empty_like(spectra)
    for fold in range(choice.folds):
        held_out = choice.held_out(fold)
        kriged[held_out] = _kriged(
            images,
            response,
            pixels[~held_out],
            spectra[~held_out],
            at_pixels=pixels[held_out],
            correlation_length=correlation_length,
        )
    errors = [relative_error((1.0 - w) * spectralized + w * kriged, spectra) for w in WEIGHTS]
    means = np.array([float(np.mean(e)) for e in errors])
    best = int(np.argmin(means))
    return KrigingWeight(
        float(WEIGHTS[best]),
        {
            "spectralization": float(means[0]),
            "kriging": float(means[-1]),
            "blend": float(means[best]),
        },
        errors[best],
    )


def kriged_estimate(
    rgb: np.ndarray, response: np.ndarray, known_pixels: np.ndarray, known_spectra: np.ndarray
) -> np.ndarray:
    """Murakami's kriged estimate of every pixel of ``rgb`` from the spots, ``(H, W, K)``, its
    correction on a grid of :data:`GRID_PER_LENGTH` points per correlation length."""
    images = np.asarray(rgb, dtype=np.float64)
    length = default_correlation_length(*images.shape[:2])
    return _kriged(
        images,
        response,
        np.asarray(known_pixels),
        np.asarray(known_spectra, dtype=np.float64),
        grid_step=max(1, int(length // GRID_PER_LENGTH)),
    )


def blend_with_kriging(
    spectralized: np.ndarray,
    rgb: np.ndarray,
    response: np.ndarray,
    known_pixels: np.ndarray,
    known_spectra: np.ndarray,
    kriging_weight: float,
) -> np.ndarray:
    """``(1 - kriging_weight) * spectralized + kriging_weight *`` Murakami's kriged estimate
    from the spots (:func:`kriged_estimate`); the spectralization itself where the weight is
    0. ``spectralized``: ``(H, W, K)``."""
    if not 0.0 <= kriging_weight <= 1.0:
        raise InputError(f"kriging_weight: expected a weight in [0, 1], got {kriging_weight}")
    if kriging_weight == 0.0:
        return spectralized
    kriged = kriged_estimate(rgb, response, known_pixels, known_spectra)
    return (1.0 - kriging_weight) * spectralized + kriging_weight * kriged
