"""Hierarchical spectralization (thesis section 11.2): the energy solved on a lattice of pixels,
the others from their nearest solved samples in appearance space.

The thesis proposes to let the optimization deal with the image's global content and to
reconstruct locally at low cost. Here the energy of Eq. 6.10 is solved on every
``stride``-th pixel of every ``stride``-th row plus the pixels with known spectra, linked by the
appearance graph of those samples alone (Eq. 6.3, the same appearance points as the whole
image's); every other pixel then takes the mean of its ``neighbours`` nearest samples in
appearance space, weighted by inverse distance, each scaled by the ratio of the pixel's
brightness (sum of camera values) to the sample's, so that shading within a material carries
over as a scale (locally, spectra proportional to the camera values, as Hardeberg's and Dong's
local methods assume). :func:`choose_prior_on_samples` cross-validates the prior on the same
lattice: the spots are samples, so each held-out spot is predicted by the samples' solve.

On the twelve real-reflectance mosaics and blends of ``recon.experiments.real_images`` at
192 px (thesis prior, RGBXY, 1 % RGB noise), with ``stride`` 2 and 4 neighbours, the error
(Eq. 6.8) is 0.65-1.01 of the plain solve's with spots at 1 % of the pixels and 0.64-0.98 with
chapter 7's 250 spots (0.80-1.02 with the regression prior); at a megapixel the solve and graph
take a third of the plain solve's time (BENCHMARKS.md, "Hierarchical spectralization"); in the
learned appearance space it was worse (:data:`SPACES`). The samples' sparser graph links each
pixel further, so the spots' information spreads further per link, and the extension averages
four solved samples.

References
----------
- The thesis, Eq. 6.3, 6.5, 6.8 and 6.10; section 11.2 (a hierarchical reconstruction).
- Hardeberg, J. Y. (2002). Acquisition and Reproduction of Color Images: Colorimetric and
  Multispectral Approaches.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from pykdtree.kdtree import KDTree

from recon.errors import InputError
from recon.spectralize.appearance import NeighbourGraph, appearance_neighbours, appearance_points
from recon.spectralize.prior_choice import FOLDS, PriorChoice, choose_prior, spot_labels
from recon.spectralize.solve import PointSpectra, reconstruct

__all__ = [
    "EXTENSION_NEIGHBOURS",
    "MIN_PIXELS",
    "SPACES",
    "SAMPLE_STRIDE",
    "SampledImage",
    "choose_prior_on_samples",
    "extend_from_samples",
    "lattice_samples",
    "on_lattice",
    "reconstruct_image",
    "reconstruct_on_samples",
    "stride_for",
]

SAMPLE_STRIDE = 2
"""Every ``SAMPLE_STRIDE``-th pixel of every ``SAMPLE_STRIDE``-th row is solved (a quarter of
them; a sixteenth with 4 was worse than the plain solve on one of twelve cases, 1.37x)."""
SPACES = frozenset({"rgb", "rgbxy"})
"""The appearance spaces ``spectwin spectralize`` solves hierarchically. In the learned
space (:mod:`recon.spectralize.learned_appearance`) the hierarchy was worse than every pixel
solved: 1.31 against 1.03 % on the clothes blend and 0.94 against 0.65 % on the colour checker
blend at 600 px (spots at 1 %, thesis prior), where the learned space's neighbours already carry
the smooth structure that the lattice thins out."""
MIN_PIXELS = 100_000
"""Smallest image solved hierarchically by ``spectwin spectralize``: the lattice must be
fine against the image's structures. At 96 x 96 px (chapter 7's 250 spots) the hierarchy was
worse than the plain solve on 6 of the 24 cases and priors (up to 1.43x: 190 materials in 190
cells of about 48 px), at 192 px on 2 of 24 by at most 2 %, at 600 and 1000 px on none."""
EXTENSION_NEIGHBOURS = 4
"""Solved samples each other pixel is made from (1 was worse than 4 on the three cases tried)."""
_CHUNK = 65_536  # pixels extended at a time (their neighbours' spectra held at once)


def stride_for(image_shape: tuple[int, ...], stride: int = SAMPLE_STRIDE) -> int:
    """The lattice stride an image of ``image_shape`` (rows, columns first) is solved with in
    the spaces of :data:`SPACES`: ``stride`` from :data:`MIN_PIXELS` pixels, else 1 (every
    pixel)."""
    return stride if image_shape[0] * image_shape[1] >= MIN_PIXELS else 1


def on_lattice(appearance: str, stride: int) -> bool:
    """Whether the space ``appearance`` is solved on a lattice of ``stride`` (from
    :func:`stride_for`): a stride above 1 and a space of :data:`SPACES`."""
    return stride > 1 and appearance in SPACES


def reconstruct_image(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    point_spectra: PointSpectra,
    stride: int,
    graph: NeighbourGraph | None = None,
    initial: np.ndarray | None = None,
    **options: Any,
) -> np.ndarray:
    """Every pixel's spectra, ``(H, W, K)``: :func:`reconstruct_on_samples` where the space
    ``options["appearance"]`` is solved on the lattice of ``stride`` (:func:`on_lattice`), else
    :func:`recon.spectralize.solve.reconstruct` of every pixel on ``graph`` (found there unless
    given) from ``initial``."""
    if on_lattice(options["appearance"], stride):
        return reconstruct_on_samples(
            rgb, response, point_spectra=point_spectra, stride=stride, **options
        )
    return np.asarray(
        reconstruct(
            rgb, response, point_spectra=point_spectra, graph=graph, initial=initial, **options
        ).spectra
    )


def lattice_samples(
    image_shape: tuple[int, int], known_pixels: np.ndarray, stride: int = SAMPLE_STRIDE
) -> np.ndarray:
    """Sorted flat indices of the lattice (every ``stride``-th pixel of every ``stride``-th
    row, from ``stride // 2``) and the known pixels.

    Examples
    --------
    >>> lattice_samples((4, 4), [0], 2).tolist()
    [0, 5, 7, 13, 15]
    """
    if not (isinstance(stride, (int, np.integer)) and stride >= 1):
        raise InputError(f"stride: expected an integer >= 1, got {stride!r}")
    lattice = np.zeros(image_shape, dtype=bool)
    lattice[stride // 2 :: stride, stride // 2 :: stride] = True
    lattice.flat[np.asarray(known_pixels, dtype=np.intp)] = True
    return np.flatnonzero(lattice)


def extend_from_samples(
    points: np.ndarray,
    camera_values: np.ndarray,
    samples: np.ndarray,
    sample_spectra: np.ndarray,
    neighbours: int = EXTENSION_NEIGHBOURS,
) -> np.ndarray:
    """Every pixel's spectrum from its ``neighbours`` nearest samples in appearance space
    (module description); the samples keep their own.

    This is scikit-learn's ``KNeighborsRegressor(neighbours, weights="distance")`` fitted to
    the samples' spectra divided by their brightness, times every pixel's brightness (the same
    to 1e-15 on a million random points), written out because pykdtree answers the queries in
    a fifth of the time there (7 s against 39 s) and the chunks bound the memory.

    Parameters
    ----------
    points
        ``(n, d)`` appearance points of every pixel.
    camera_values
        ``(n, C)`` camera values of every pixel.
    samples
        Flat indices of the solved pixels.
    sample_spectra
        ``(len(samples), K)`` their spectra.
    neighbours
        Samples per pixel.

    Returns
    -------
    numpy.ndarray
        ``(n, K)``.

    Examples
    --------
    >>> import numpy as np
    >>> values = np.array([[1.0, 1.0], [2.0, 2.0], [4.0, 4.0]])  # one material, shaded
    >>> extend_from_samples(values / values.sum(1, keepdims=True), values, np.array([0]),
    ...                     np.array([[0.2, 0.4]]), neighbours=1).tolist()
    [[0.2, 0.4], [0.4, 0.8], [0.8, 1.6]]
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    samples = np.asarray(samples, dtype=np.intp)
    count = min(int(neighbours), samples.size)
    tree = KDTree(np.ascontiguousarray(points[samples]))
    brightness = np.asarray(camera_values, dtype=np.float64).sum(axis=1)
    sample_brightness = brightness[samples]
    extended = np.empty((points.shape[0], sample_spectra.shape[1]))
    for start in range(0, points.shape[0], _CHUNK):
        rows = slice(start, start + _CHUNK)
        distance, nearest = tree.query(points[rows], k=count)
        distance = distance.reshape(-1, count)
        nearest = nearest.reshape(-1, count).astype(np.intp)
        weights = 1.0 / np.maximum(distance, 1e-12)
        weights /= weights.sum(axis=1, keepdims=True)
        below = sample_brightness[nearest]
        scale = np.divide(brightness[rows, None], below, out=np.ones_like(below), where=below > 0)
        extended[rows] = np.einsum("pk,pkb->pb", weights * scale, sample_spectra[nearest])
    extended[samples] = sample_spectra
    return extended


@dataclass(frozen=True)
class SampledImage:
    """An image's lattice of samples (:func:`lattice_samples`) and what its solves share: the
    ``samples`` (sorted flat indices), the appearance ``points`` of every pixel, the
    ``graph`` among the samples (Eq. 6.3, in those points), every pixel's ``camera_values``
    ``(n, C)`` and the ``known`` pixels' indices among the samples."""

    samples: np.ndarray
    points: np.ndarray
    graph: NeighbourGraph
    camera_values: np.ndarray
    known: np.ndarray

    @classmethod
    def of(
        cls, rgb: np.ndarray, known_pixels: np.ndarray, stride: int, options: dict[str, Any]
    ) -> tuple[SampledImage, dict[str, Any]]:
        """The lattice of ``rgb`` (``(H, W, C)``) with the ``known_pixels`` among its samples,
        linked by the ``neighbours`` (3) of ``options`` in their space ``appearance``
        (``"rgbxy"``, with ``appearance_options``); and the other ``options`` as a solve on the
        samples takes them: with the samples' graph, and RGB as the space that links
        components without data (module description)."""
        taken = sorted({"graph", "p_dyn", "band_images", "device_integrals"} & set(options))
        if taken:
            raise InputError(
                f"{', '.join(taken)}: the hierarchical reconstruction takes point spectra and "
                "an appearance space only"
            )
        images = np.asarray(rgb, dtype=np.float64)
        if images.ndim != 3:
            raise InputError(f"rgb: expected (H, W, C) camera values, got shape {images.shape}")
        solve = dict(options)
        appearance = solve.pop("appearance", "rgbxy")
        appearance_options = solve.pop("appearance_options", None) or {}
        neighbours = solve.setdefault("neighbours", 3)
        pixels = np.asarray(known_pixels, dtype=np.intp)
        samples = lattice_samples(images.shape[:2], pixels, stride)
        points = appearance_points(images[None], appearance, **appearance_options)
        graph = appearance_neighbours(np.ascontiguousarray(points[samples]), k=neighbours)
        flat = images.reshape(-1, images.shape[-1])
        sampled = cls(samples, points, graph, flat, np.searchsorted(samples, pixels))
        return sampled, solve | {"graph": graph, "appearance": "rgb"}

    def sample_values(self) -> np.ndarray:
        """``(1, n_samples, C)``: the samples' camera values as an image of one row, the
        layout the solves take them in."""
        return self.camera_values[self.samples][None]


def reconstruct_on_samples(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    point_spectra: PointSpectra,
    stride: int = SAMPLE_STRIDE,
    **options: Any,
) -> np.ndarray:
    """The hierarchical reconstruction of the module description.

    Parameters
    ----------
    rgb, response
        ``(H, W, C)`` camera values and the ``(K, C)`` response, as in
        :func:`recon.spectralize.solve.reconstruct`.
    point_spectra
        The known spectra at flat pixel indices of ``rgb`` (Eq. 6.10), an array of spectra.
    stride
        Of the lattice solved (:data:`SAMPLE_STRIDE`).
    **options
        The options of :func:`recon.spectralize.solve.reconstruct`: ``appearance`` (default
        ``"rgbxy"``), ``appearance_options`` and ``neighbours``, the graph's (Eq. 6.3-6.6),
        found for the whole image and linked among the samples (the extension uses the same
        points), and the others (``weights``, ``prior``, ``tol``, ``progress``, ...); not
        ``graph`` or ``p_dyn``.

    Returns
    -------
    numpy.ndarray
        ``(H, W, K)`` spectra.
    """
    sampled, solve = SampledImage.of(rgb, point_spectra.pixels, stride, options)
    spectra = np.asarray(point_spectra.spectra, dtype=np.float64)
    solved = reconstruct(
        sampled.sample_values(),
        response,
        point_spectra=PointSpectra(sampled.known, spectra),
        **solve,
    ).spectra.reshape(sampled.samples.size, -1)
    extended = extend_from_samples(sampled.points, sampled.camera_values, sampled.samples, solved)
    return extended.reshape(*np.shape(rgb)[:2], -1)


def choose_prior_on_samples(
    rgb: np.ndarray,
    response: np.ndarray,
    known_pixels: np.ndarray,
    known_spectra: np.ndarray,
    *,
    folds: int = FOLDS,
    stride: int = SAMPLE_STRIDE,
    progress: bool = False,
    **options: Any,
) -> PriorChoice:
    """:func:`recon.spectralize.choose_prior` with every fold solved on the lattice, as
    :func:`reconstruct_on_samples` solves: the held-out spots are samples, so each is
    predicted by the samples' solve itself, and the folds measure the reconstruction that is
    used.

    Parameters
    ----------
    rgb, response, known_pixels, known_spectra, folds, progress
        As in :func:`recon.spectralize.choose_prior`, ``rgb`` ``(H, W, C)``; the spots are
        numbered on the image's own grid.
    stride, **options
        As in :func:`reconstruct_on_samples`.

    Returns
    -------
    PriorChoice
        In the order of ``known_pixels``; without ``fold_spectra`` (the folds' spectra are
        the samples', no starting guess for the image).
    """
    pixels = np.asarray(known_pixels, dtype=np.intp)
    sampled, solve = SampledImage.of(rgb, pixels, stride, options)
    choice = choose_prior(
        sampled.sample_values(),
        response,
        sampled.known,
        known_spectra,
        folds=folds,
        spot_of_pixel=spot_labels(pixels, (1, *np.shape(rgb)[:2]), folds),
        progress=progress,
        **solve,
    )
    return dataclasses.replace(choice, fold_spectra=None)
