"""Which appearance prior fits an image: chosen from known spectra held out of the solve.

The prior of Eq. 6.3 can hold alike between neighbours either the spectra themselves (the
thesis) or their difference from a linear regression on the camera values (``prior=
"regression"`` of :func:`recon.spectralize.solve.build_problem`). Which one reconstructs an
image better depends on the image: the plain prior wins where neighbours share a material and the
RGB noise is what separates them (mosaics of materials), the regression prior where brightness and
colour change smoothly within a material (shading, blends). :func:`choose_prior` decides from the
data at hand by cross-validation over the spectral spots (five folds unless told otherwise): it
leaves every fifth spot out in turn, reconstructs the image with each prior from the other spots
and keeps the prior with the smaller mean relative error (Eq. 6.8) over all spots, each predicted
while it was left out (push-broom lines are cut into segments first). It costs ``folds``
solves, each of both priors together (:func:`recon.spectralize.joint.reconstruct_priors`: one
Kronecker solve with twice the columns, its spectra assembled at the held-out spots only but
in the last fold, whose whole images are kept as the starting guess of the final solve), on
the appearance graph found once for the image (:func:`recon.spectralize.solve.neighbour_graph`).
``folds=3`` is the cheap setting of ``spectwin spectralize``; BENCHMARKS.md, "Spectralizing a
user's image", measures its cost against a single solve.

On the 21 mosaic and real-image cases of ``benchmarks/spectralize_real.py`` a single held-out
fold chose the worse prior 8 times (once losing the 30 % margin over the best peer), five folds
6 times (never losing it): where the two priors are close, the left-out spots of a mosaic often
sit in cells that no other spot reaches.

References
----------
- The thesis, Eq. 6.3, 6.8 and 6.10; Sec. 6.1 (the inverse matrix of Hardeberg that the
  regression prior uses as its base).
- Hastie, T., Tibshirani, R., & Friedman, J. (2009). The Elements of Statistical Learning,
  2nd ed., Sec. 7.10 (cross-validation).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from recon.errors import InputError
from recon.metrics import relative_error
from recon.progress import progress_steps
from recon.spectralize.joint import reconstruct_priors
from recon.spectralize.learned_appearance import LEARNED_SPACES, fitted_on
from recon.spectralize.solve import PRIORS, PointSpectra, graph_for

__all__ = ["PriorChoice", "choose_prior", "spot_labels"]

FOLDS = 5
"""Folds of the cross-validation: fold ``f`` holds out the spots whose number (row-major order of
their first pixel) is ``f`` modulo ``FOLDS``."""


@dataclass(frozen=True)
class PriorChoice:
    """The chosen ``prior``, the mean relative error (Eq. 6.8, %) per prior over the known
    pixels, each predicted from the other folds, and the number of ``spots`` (or line
    segments). ``pixel_errors``: per prior, the error (Eq. 6.8, %) of every known pixel
    predicted while its fold was held out, in the order of ``known_pixels``; ``spot_of_pixel``:
    the spot (or segment) number of every known pixel, which is held out in fold
    ``spot % folds``. ``held_out_spectra``: per prior, every known pixel's spectrum predicted
    while its fold was held out, ``(m, K)``. ``fold_spectra``: the chosen prior's
    reconstruction of the last fold at every pixel (the leading shape of ``rgb``, then ``K``),
    a starting guess for the solve from all spots (``initial=`` of
    :func:`~recon.spectralize.solve.reconstruct`), which it leaves fewer iterations to do."""

    prior: str
    held_out_errors: dict[str, float]
    spots: int
    folds: int = FOLDS
    pixel_errors: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    spot_of_pixel: np.ndarray = field(default_factory=lambda: np.empty(0, int), repr=False)
    held_out_spectra: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    fold_spectra: np.ndarray | None = field(default=None, repr=False)

    def held_out(self, fold: int) -> np.ndarray:
        """``(m,)`` bool: the known pixels that fold ``fold`` held out."""
        return _held_out(self.spot_of_pixel, self.folds, fold)


def _held_out(spots: np.ndarray, folds: int, fold: int) -> np.ndarray:
    """The known pixels of the spots that fold ``fold`` of ``folds`` holds out (:data:`FOLDS`)."""
    return np.asarray(spots % folds == fold)


def spot_labels(
    pixels: np.ndarray, image_shape: tuple[int, int, int], folds: int = FOLDS
) -> np.ndarray:
    """Spot number of every known pixel: 4-connected groups of known pixels within one image;
    where there are fewer than ``folds`` groups (push-broom lines), each is cut into
    ``2 folds`` segments along its longer side."""
    mask = np.zeros(int(np.prod(image_shape)), dtype=bool)
    mask[pixels] = True
    within_image = np.zeros((3, 3, 3), dtype=bool)
    within_image[1] = ndimage.generate_binary_structure(2, 1)
    labels, count = ndimage.label(mask.reshape(image_shape), structure=within_image)
    spots = labels.ravel()[pixels] - 1
    if count >= folds:
        return spots
    _, rows, cols = np.unravel_index(pixels, image_shape)
    segments = np.empty_like(spots)
    for spot in range(count):
        members = np.flatnonzero(spots == spot)
        along = rows[members] if np.ptp(rows[members]) >= np.ptp(cols[members]) else cols[members]
        rank = np.argsort(np.argsort(along, kind="stable"), kind="stable")
        segments[members] = spot * 2 * folds + rank * 2 * folds // members.size
    return np.unique(segments, return_inverse=True)[1]


def choose_prior(
    rgb: np.ndarray,
    response: np.ndarray,
    known_pixels: np.ndarray,
    known_spectra: np.ndarray,
    *,
    folds: int = FOLDS,
    spot_of_pixel: np.ndarray | None = None,
    progress: bool = False,
    **options: Any,
) -> PriorChoice:
    """Pick the appearance prior (``"spectra"`` or ``"regression"``) by held-out spots.

    Parameters
    ----------
    rgb, response
        As in :func:`recon.spectralize.solve.reconstruct`: ``(H, W, C)`` or ``(N, H, W, C)``
        camera values and the ``(K, C)`` response.
    known_pixels, known_spectra
        Flat pixel indices and their ``(m, K)`` spectra (Eq. 6.10), in spots of one or more
        adjacent pixels (at least ``FOLDS``) or in lines (push-broom), which are cut into
        segments.
    folds
        Folds of the cross-validation (at least 2): fold ``f`` holds out the spots whose number
        (row-major order of their first pixel) is ``f`` modulo ``folds``.
    spot_of_pixel
        ``(m,)`` the spot number of every known pixel (from 0, numbered as above), where the
        layout of ``rgb`` does not tell which pixels are adjacent (the lattice of samples of
        :mod:`recon.spectralize.hierarchy`, laid out as one row); ``None``: found from it.
    progress
        Show a progress bar over the folds.
    **options
        The other energy and solver options of :func:`~recon.spectralize.solve.reconstruct`
        (``appearance``, ``neighbours``, ``weights``, ``p_dyn``, ``tol``, ...), used for every
        trial solve, among them ``graph`` (:func:`~recon.spectralize.solve.neighbour_graph` of
        these options, found here if not given); ``prior`` is the one option it sets itself.
        A learned appearance space (:data:`~recon.spectralize.learned_appearance.LEARNED_SPACES`)
        is refitted in every fold on the spots the fold keeps, and its graph found anew, so
        that no held-out spectrum shapes the links it is predicted through; its
        ``known_pixels`` and ``known_spectra`` options and ``graph`` are those of the solve
        from all spots, which the folds do not use.

    Returns
    -------
    PriorChoice

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> response, basis = rng.random((8, 3)), rng.random((3, 8))
    >>> truth = (rng.random((12, 12, 3)) @ basis)  # spectra in the span of three
    >>> pixels = np.arange(0, 144, 7)
    >>> choice = choose_prior(truth @ response, response, pixels, truth.reshape(-1, 8)[pixels])
    >>> choice.prior, choice.spots
    ('regression', 21)
    """
    if "prior" in options:
        raise InputError("prior: choose_prior tries every prior; do not pass one")
    if not (isinstance(folds, (int, np.integer)) and folds >= 2):
        raise InputError(f"folds: expected an integer >= 2, got {folds!r}")
    images = np.asarray(rgb, dtype=np.float64)
    pixels = np.asarray(known_pixels)
    spectra = np.asarray(known_spectra, dtype=np.float64)
    if pixels.ndim != 1 or spectra.shape[:1] != pixels.shape:
        raise InputError(
            f"known_pixels, known_spectra: expected m indices and (m, K) spectra, got shapes "
            f"{pixels.shape} and {spectra.shape}"
        )
    if images.ndim not in (3, 4):
        raise InputError(
            f"rgb: expected (H, W, C) or (N, H, W, C) camera values, got shape {images.shape}"
        )
    pixel_grid = images.shape[:-1] if images.ndim == 4 else (1, *images.shape[:-1])
    if pixels.size and (pixels.min() < 0 or pixels.max() >= np.prod(pixel_grid)):
        raise InputError(
            f"known_pixels: expected indices in [0, {np.prod(pixel_grid)}), got "
            f"[{pixels.min()}, {pixels.max()}]"
        )
    if spot_of_pixel is None:
        spots = spot_labels(pixels, pixel_grid, folds)
    else:
        spots = np.asarray(spot_of_pixel)
        if spots.shape != pixels.shape:
            raise InputError(
                f"spot_of_pixel: expected one spot number per known pixel ({pixels.size}), "
                f"got shape {spots.shape}"
            )
    count = int(spots.max()) + 1 if spots.size else 0
    if count < folds:
        raise InputError(
            f"known_pixels: choose_prior needs at least {folds} separate spots (or lines long "
            f"enough to cut into {2 * folds} segments) to hold one in {folds} out, got {count}"
        )
    graph = options.pop("graph", None)
    learned = options.get("appearance") in LEARNED_SPACES
    if graph is None and not learned:
        graph = graph_for(images, options)
    predicted = {prior: np.empty_like(spectra) for prior in PRIORS}
    with progress_steps("choosing the prior: folds", folds, enabled=progress) as advance:
        for fold in range(folds):
            held_out = _held_out(spots, folds, fold)
            last = fold == folds - 1  # its whole images are kept as the starting guess
            fold_options = options
            if learned:  # the space refitted without the held-out spots
                fold_options = fitted_on(options, pixels[~held_out], spectra[~held_out])
                graph = graph_for(images, fold_options)
            estimates = reconstruct_priors(
                images,
                response,
                point_spectra=PointSpectra(pixels[~held_out], spectra[~held_out]),
                at_pixels=None if last else pixels[held_out],
                graph=graph,
                **fold_options,
            )
            for prior, estimate in estimates.items():
                rows = (
                    estimate.reshape(-1, spectra.shape[1])[pixels[held_out]] if last else estimate
                )
                predicted[prior][held_out] = rows
            advance()
    pixel_errors = {prior: relative_error(predicted[prior], spectra) for prior in PRIORS}
    errors = {prior: float(np.mean(values)) for prior, values in pixel_errors.items()}
    chosen = min(errors, key=errors.__getitem__)
    return PriorChoice(
        chosen, errors, count, folds, pixel_errors, spots, predicted, estimates[chosen]
    )
