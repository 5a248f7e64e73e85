"""Spectral exposure plan and band schedule of the LED dome with a spectral camera (thesis 10.4).

The dome's RGB cameras photograph every light direction with an HDR exposure set (thesis:
:math:`t_i \\in \\{50, 186, 666, 2500\\}` ms, :math:`\\sum_i t_i` = 3.402 s per RGB image) while
the monochrome camera behind the tunable filter exposes spectral bands in parallel. Three steps
plan the spectral side:

1. Band exposure times (thesis section 10.4, line "For the spectral camera, we calculated the
   exposure time as ..."): :math:`t_\\lambda = t_{base} / \\sqrt{E(\\lambda) L(\\lambda)}`, with
   :math:`E` the sensitivity of camera and filter and :math:`L` the light spectrum per band.
   Weakly supported bands get longer exposures, but only by the square root of their deficit:
   the plan accepts more noise there (:func:`spectral_exposures`).
2. Filter sizes (Figure 10.5): the reconstruction's Gaussian filter :math:`F` (Eq. 10.1) of each
   band must average the band's noise away, so noisier bands get larger filters, with
   :math:`\\sigma` = size / 5 (:func:`filter_sizes`, :func:`gaussian_noise_factor`).
3. Band schedule (thesis section 10.4, "When using a binpacking algorithm ..."): every band
   exposure is finished during one RGB image (one light source); an image lasts as long as the
   longer of the RGB exposure set and the band exposures assigned to it. Assigning bands to
   images so that the summed image time is smallest is a bin-packing problem, solved exactly
   here as a mixed-integer linear program (:func:`schedule_bands`, :func:`fewest_images`).
   The thesis reports 30 bands in 8 RGB images at about +41 % total exposure time, and 10 RGB
   images with the noisiest bands taken twice at about +61 %.

References
----------
- The thesis, section 10.4 (exposure times :math:`t_\\lambda`, band scheduling by bin packing,
  the +41 % and +61 % figures) and Figure 10.5 (exposure times and filter sizes,
  :math:`\\sigma` = filter size / 5); Eq. 10.1 (the filtered band term).
- Huangfu, Q., & Hall, J. A. J. (2018). Parallelizing the dual revised simplex method.
  Mathematical Programming Computation, 10(1), 119-142. doi:10.1007/s12532-017-0130-5
  (HiGHS, the MILP solver behind ``scipy.optimize.milp``).
- Martello, S., & Toth, P. (1990). Knapsack Problems: Algorithms and Computer Implementations.
  Wiley. Chapter 8 (bin packing).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import optimize, sparse

from recon.errors import SpectwinInputError

__all__ = [
    "FILTER_SIZE_PER_SIGMA",
    "THESIS_RGB_EXPOSURES_S",
    "BandSchedule",
    "fewest_images",
    "filter_sizes",
    "gaussian_noise_factor",
    "schedule_bands",
    "spectral_exposures",
]

THESIS_RGB_EXPOSURES_S = (0.05, 0.186, 0.666, 2.5)
"""HDR exposure set of the dome's RGB cameras (thesis section 10.4): 3.402 s per RGB image."""

FILTER_SIZE_PER_SIGMA = 5.0
"""Filter size over the Gaussian's standard deviation (thesis Figure 10.5: sigma = size / 5)."""


def _positive_vector(name: str, values: object, size: int | None = None) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or array.size == 0 or (size is not None and array.size != size):
        expected = f"({size},)" if size is not None else "a non-empty 1-D array"
        raise SpectwinInputError(
            f"{name}: expected one value per band, shape {expected}, got shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise SpectwinInputError(f"{name}: expected finite values, found NaN or infinity")
    if np.any(array <= 0):
        raise SpectwinInputError(
            f"{name}: expected positive values, got {array[array <= 0][0]:g} at index "
            f"{int(np.flatnonzero(array <= 0)[0])}"
        )
    return array


def _positive_scalar(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SpectwinInputError(f"{name}: expected a positive number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise SpectwinInputError(f"{name}: expected a finite, positive number, got {value}")
    return float(value)


def spectral_exposures(
    base_s: float,
    sensitivity: np.ndarray,
    light: np.ndarray,
    *,
    limits_s: tuple[float, float] | None = None,
) -> np.ndarray:
    """Band exposure times :math:`t_\\lambda = t_{base} / \\sqrt{E(\\lambda) L(\\lambda)}`.

    Parameters
    ----------
    base_s
        :math:`t_{base}` in s: the exposure of a band with :math:`E L = 1`.
    sensitivity
        ``(K,)`` :math:`E(\\lambda)`, the linear response of camera, optics and filter per unit
        of ``light`` (thesis 10.3: the white reference's linearized response divided by the LED
        spectrum), positive.
    light
        ``(K,)`` :math:`L(\\lambda)`, the light spectrum per band, positive.
    limits_s
        ``(shortest, longest)`` exposure the camera can make; times are clipped into it.

    Returns
    -------
    numpy.ndarray
        ``(K,)`` exposure times in s. The signal of a grey sample grows as
        :math:`E L t_\\lambda = t_{base} \\sqrt{E L}`: weak bands are exposed longer but stay
        noisier (thesis: "we accept more noise in those spectral bands").

    References
    ----------
    The thesis, section 10.4 (exposure time of the spectral camera) and Figure 10.5.

    Examples
    --------
    >>> spectral_exposures(1.0, [4.0, 1.0], [1.0, 0.25]).tolist()
    [0.5, 2.0]
    """
    base = _positive_scalar("base_s", base_s)
    sensitivity = _positive_vector("sensitivity", sensitivity)
    light = _positive_vector("light", light, sensitivity.size)
    exposures = base / np.sqrt(sensitivity * light)
    if limits_s is None:
        return exposures
    limits = np.asarray(limits_s, dtype=np.float64)
    if limits.shape != (2,) or not np.all(np.isfinite(limits)) or not 0 < limits[0] <= limits[1]:
        raise SpectwinInputError(
            f"limits_s: expected (shortest, longest) with 0 < shortest <= longest, got {limits_s}"
        )
    return np.clip(exposures, limits[0], limits[1])


def gaussian_noise_factor(sigma_px: float | np.ndarray) -> np.ndarray:
    """Factor by which a normalized 2-D Gaussian of std ``sigma_px`` scales white noise's std.

    A filtered pixel :math:`y = \\sum_p w_p x_p` of independent pixels :math:`x_p` with equal
    variance :math:`s^2` has variance :math:`s^2 \\sum_p w_p^2`, while a locally constant signal
    passes unchanged (:math:`\\sum_p w_p = 1`). For
    :math:`w(x, y) = e^{-(x^2 + y^2) / 2\\sigma^2} / (2 \\pi \\sigma^2)`,
    :math:`\\iint w^2 = 1 / (4 \\pi \\sigma^2)`, so the std shrinks by
    :math:`1 / (2 \\sqrt{\\pi} \\sigma)`.

    The sum over a sampled kernel equals the integral to 1.6 % at :math:`\\sigma` = 0.7 px and to
    0.4 % from 0.8 px on (a kernel truncated at 3 sigma, as in ``recon.energy_terms``, adds
    0.5 %). Below 0.7 px the sampled kernel reduces noise less than this factor (at 0.5 px by
    14 % less; as :math:`\\sigma \\to 0` it keeps the noise).

    Parameters
    ----------
    sigma_px
        Standard deviation in pixels, positive.

    Returns
    -------
    numpy.ndarray
        :math:`1 / (2 \\sqrt{\\pi} \\sigma)`, same shape as ``sigma_px``.

    References
    ----------
    The thesis, Eq. 10.1 (the filter :math:`F`) and Figure 10.5 (filter sizes).

    Examples
    --------
    >>> round(float(gaussian_noise_factor(1.0)), 4)
    0.2821
    """
    sigma = np.asarray(sigma_px, dtype=np.float64)
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0):
        raise SpectwinInputError("sigma_px: expected finite, positive standard deviations in px")
    return 1.0 / (2.0 * np.sqrt(np.pi) * sigma)


def filter_sizes(relative_noise: np.ndarray, target_relative_noise: float) -> np.ndarray:
    """Gaussian filter size per band that brings its relative noise down to the target.

    With the band image's relative noise :math:`r_\\lambda` (std over mean signal of one pixel,
    pixels independent) and the factor of :func:`gaussian_noise_factor`, the filter needs
    :math:`\\sigma_\\lambda = r_\\lambda / (2 \\sqrt{\\pi} r_{target})`; its size is
    :math:`5 \\sigma_\\lambda` (Figure 10.5). Bands already at or below the target need no
    filter (size 0). Sizes below 3.5 px (:math:`\\sigma` < 0.7 px) are where a sampled kernel
    falls short of the factor: there the size is a lower bound.

    Parameters
    ----------
    relative_noise
        ``(K,)`` relative noise of each band image, non-negative.
    target_relative_noise
        Relative noise wanted after filtering, positive (Figure 10.5 is drawn for filters that
        "nearly completely cancel the noise"; the thesis found smaller ones often suffice).

    Returns
    -------
    numpy.ndarray
        ``(K,)`` filter sizes in pixels (divide by :data:`FILTER_SIZE_PER_SIGMA` for sigma).

    References
    ----------
    The thesis, section 10.4 and Figure 10.5 (filter sizes, sigma = size / 5).

    Examples
    --------
    >>> filter_sizes([0.005, 0.2], 0.01).round(2).tolist()
    [0.0, 28.21]
    """
    noise = np.asarray(relative_noise, dtype=np.float64)
    if noise.ndim != 1 or noise.size == 0:
        raise SpectwinInputError(
            f"relative_noise: expected one value per band, a non-empty 1-D array, got shape "
            f"{noise.shape}"
        )
    if not np.all(np.isfinite(noise)) or np.any(noise < 0):
        raise SpectwinInputError("relative_noise: expected finite, non-negative values per band")
    target = _positive_scalar("target_relative_noise", target_relative_noise)
    sigma = noise / (2.0 * np.sqrt(np.pi) * target)
    return np.where(noise > target, FILTER_SIZE_PER_SIGMA * sigma, 0.0)


@dataclass(frozen=True, eq=False)
class BandSchedule:
    """Band exposures assigned to RGB images.

    Attributes
    ----------
    images
        Per RGB image, the indices of the bands the spectral camera exposes meanwhile (a band
        taken twice appears in two images).
    spectral_s
        ``(n_images,)`` summed band exposure per image, s.
    image_s
        ``(n_images,)`` duration of each image, :math:`\\max(\\sum_i t_i, \\text{spectral\\_s})`.
    rgb_s
        :math:`\\sum_i t_i`, the RGB exposure set per image, s.
    total_s
        Total exposure time, the sum of ``image_s``.
    increase
        ``total_s / (n_images * rgb_s) - 1``: the extra time over RGB-only capture.
    optimal
        Whether the solver proved ``total_s`` minimal (and, from :func:`fewest_images`, the
        image count smallest); ``False`` when it stopped at its time limit.
    """

    images: tuple[tuple[int, ...], ...]
    spectral_s: np.ndarray
    image_s: np.ndarray
    rgb_s: float
    total_s: float
    increase: float
    optimal: bool

    @property
    def n_images(self) -> int:
        return len(self.images)


@dataclass(frozen=True)
class _Instance:
    """Validated scheduling input: one exposure per item, longest first."""

    exposures_s: np.ndarray  # (m,) item exposure times, non-increasing
    bands: np.ndarray  # (m,) band index of each item
    rgb_s: float
    image_limit_s: float | None


def _instance(
    band_exposures_s: np.ndarray,
    rgb_exposures_s: Sequence[float] | np.ndarray,
    repeat_bands: Sequence[int],
    image_limit_s: float | None,
) -> _Instance:
    exposures = _positive_vector("band_exposures_s", band_exposures_s)
    rgb = _positive_vector("rgb_exposures_s", rgb_exposures_s)
    repeats = np.asarray(repeat_bands)
    if repeats.size and (
        repeats.ndim != 1
        or not np.issubdtype(repeats.dtype, np.integer)
        or np.any((repeats < 0) | (repeats >= exposures.size))
        or np.unique(repeats).size != repeats.size
    ):
        raise SpectwinInputError(
            f"repeat_bands: expected distinct band indices in [0, {exposures.size}), got "
            f"{list(repeat_bands)}"
        )
    bands = np.concatenate([np.arange(exposures.size), repeats.astype(np.int64)])
    order = np.argsort(-exposures[bands], kind="stable")
    limit = None if image_limit_s is None else _positive_scalar("image_limit_s", image_limit_s)
    if limit is not None and limit < exposures.max():
        raise SpectwinInputError(
            f"image_limit_s: {limit:g} s is shorter than the longest band exposure "
            f"({exposures.max():g} s), which must fit into one image"
        )
    return _Instance(exposures[bands][order], bands[order], float(rgb.sum()), limit)


def _n_images(n_images: object, instance: _Instance) -> int:
    if isinstance(n_images, bool) or not isinstance(n_images, (int, np.integer)) or n_images < 1:
        raise SpectwinInputError(f"n_images: expected a positive integer, got {n_images!r}")
    if np.unique(instance.bands).size < instance.bands.size and n_images < 2:
        raise SpectwinInputError(
            "n_images: a band taken twice needs two different images, expected at least 2"
        )
    return int(n_images)


def _balance(instance: _Instance, image_of_item: np.ndarray, n: int) -> np.ndarray:
    """Move or swap bands out of the longest image while that shortens it and keeps the total.

    The minimum total is usually shared by many assignments (any one whose images are all
    spectral-bound, however lopsided). Moving item :math:`a` from the longest image (load
    :math:`L_{max}`) to image :math:`b`, or swapping it for a shorter item :math:`c` there,
    shifts :math:`d = t_a - t_c > 0`; with :math:`L_b + d < L_{max}` this lowers the sum of
    squared loads, so the loop ends. A step is taken only if the total does not grow and no
    image gets a band twice.
    """
    t, rgb_s, bands = instance.exposures_s, instance.rgb_s, instance.bands
    image_of_item = image_of_item.copy()
    items = np.arange(t.size)

    def improving_step(loads: np.ndarray, longest: int) -> tuple[int, int, int] | None:
        for a in items[image_of_item == longest]:
            for image in np.argsort(loads, kind="stable"):
                inside = items[image_of_item == image]
                for c in (-1, *inside) if image != longest else ():
                    shift = t[a] - (t[c] if c >= 0 else 0.0)
                    change = (
                        max(rgb_s, loads[longest] - shift)
                        - max(rgb_s, loads[longest])
                        + max(rgb_s, loads[image] + shift)
                        - max(rgb_s, loads[image])
                    )
                    if (
                        shift > 0
                        and loads[image] + shift < loads[longest]
                        and change <= 1e-12
                        and bands[a] not in bands[inside[inside != c]]
                        and (
                            c < 0
                            or bands[c] not in bands[(image_of_item == longest) & (items != a)]
                        )
                    ):
                        return a, int(image), c
        return None

    while True:
        loads = np.bincount(image_of_item, weights=t, minlength=n)
        longest = int(np.argmax(loads))
        step = improving_step(loads, longest)
        if step is None:
            return image_of_item
        a, image, c = step
        image_of_item[a] = image
        if c >= 0:
            image_of_item[c] = longest


def _solve(instance: _Instance, n: int, time_limit_s: float) -> tuple[BandSchedule | None, bool]:
    """Minimum-total assignment of the instance's items to ``n`` images, and whether the solver
    decided the problem (proved the optimum or that no assignment exists) within its time limit.

    Variables: :math:`x_{jb}` = 1 when item :math:`j` is exposed during image :math:`b`, and the
    overflow :math:`o_b \\ge \\sum_j t_j x_{jb} - R`, :math:`o_b \\ge 0`; minimize
    :math:`\\sum_b o_b` (the total is :math:`n R + \\sum_b o_b`). Each item goes to one image,
    copies of one band to different images, and item :math:`j` (longest first) to one of the
    first :math:`j + 1` images, which removes the images' interchangeability without losing
    an optimum. The solution is then balanced by :func:`_balance`.
    """
    t, rgb_s = instance.exposures_s, instance.rgb_s
    m = t.size
    item_to_image = sparse.kron(t[None, :], sparse.eye_array(n), format="csr")
    rows = [
        sparse.hstack(
            [sparse.kron(sparse.eye_array(m), np.ones((1, n))), sparse.csr_array((m, n))]
        ),
        sparse.hstack([item_to_image, -sparse.eye_array(n)]),
    ]
    lower = [np.ones(m), np.full(n, -np.inf)]
    upper = [np.ones(m), np.full(n, rgb_s)]
    if instance.image_limit_s is not None:
        rows.append(sparse.hstack([item_to_image, sparse.csr_array((n, n))]))
        lower.append(np.full(n, -np.inf))
        upper.append(np.full(n, instance.image_limit_s))
    for band in np.unique(instance.bands):
        copies = np.flatnonzero(instance.bands == band)
        if copies.size > 1:
            selector = sparse.csr_array(
                (np.ones(copies.size), (np.zeros(copies.size), copies)), shape=(1, m)
            )
            rows.append(
                sparse.hstack(
                    [sparse.kron(selector, sparse.eye_array(n)), sparse.csr_array((n, n))]
                )
            )
            lower.append(np.full(n, -np.inf))
            upper.append(np.ones(n))
    allowed = (np.arange(n)[None, :] <= np.arange(m)[:, None]).ravel()
    result = optimize.milp(
        np.concatenate([np.zeros(m * n), np.ones(n)]),
        constraints=optimize.LinearConstraint(
            sparse.vstack(rows).tocsr(), np.concatenate(lower), np.concatenate(upper)
        ),
        integrality=np.concatenate([np.ones(m * n), np.zeros(n)]),
        bounds=optimize.Bounds(0.0, np.concatenate([allowed, np.full(n, np.inf)])),
        options={"time_limit": time_limit_s, "mip_rel_gap": 1e-6},
    )
    decided = result.status in (0, 2)  # optimal, infeasible; 1: time limit reached
    if result.x is None:
        return None, decided
    image_of_item = _balance(instance, np.round(result.x[: m * n]).reshape(m, n).argmax(axis=1), n)
    spectral = np.bincount(image_of_item, weights=t, minlength=n)
    image_s = np.maximum(spectral, rgb_s)
    total = float(image_s.sum())
    schedule = BandSchedule(
        images=tuple(
            tuple(sorted(int(b) for b in instance.bands[image_of_item == image]))
            for image in range(n)
        ),
        spectral_s=spectral,
        image_s=image_s,
        rgb_s=rgb_s,
        total_s=total,
        increase=total / (n * rgb_s) - 1.0,
        optimal=decided,
    )
    return schedule, decided


def schedule_bands(
    band_exposures_s: np.ndarray,
    n_images: int,
    *,
    rgb_exposures_s: Sequence[float] | np.ndarray = THESIS_RGB_EXPOSURES_S,
    repeat_bands: Sequence[int] = (),
    image_limit_s: float | None = None,
    time_limit_s: float = 10.0,
) -> BandSchedule:
    """Assign every band exposure to one of ``n_images`` RGB images, minimizing total time.

    The spectral camera exposes in parallel to the RGB cameras, and a band exposure is finished
    during one image (one light source); an image therefore lasts
    :math:`\\max(\\sum_i t_i, \\sum_{\\lambda \\in image} t_\\lambda)`. The assignment that
    minimizes the sum of image durations is found exactly by mixed-integer linear programming
    (HiGHS via ``scipy.optimize.milp``); bands with a wide spread of exposure times, as in the
    thesis, solve in well under a second. Among equally short schedules the solver's pick can
    be lopsided; bands are then moved or swapped out of the longest image while that shortens
    it without lengthening the total. Proving the optimum is slowest when the band exposures
    sum to about ``n_images`` RGB sets (a tight bin packing): there ``time_limit_s`` may end
    the search.

    Parameters
    ----------
    band_exposures_s
        ``(K,)`` band exposure times :math:`t_\\lambda` in s (e.g. from
        :func:`spectral_exposures`).
    n_images
        Number of RGB images (light sources) to spread the bands over.
    rgb_exposures_s
        The RGB cameras' exposure set per image (default: the thesis's 50, 186, 666, 2500 ms).
    repeat_bands
        Indices of bands exposed twice, in two different images (the thesis repeats the
        noisiest bands).
    image_limit_s
        Longest allowed image duration, or ``None`` for no limit.
    time_limit_s
        Solver time limit; if it is reached the best schedule found is returned with
        ``optimal=False``.

    Returns
    -------
    BandSchedule
        The assignment, per-image and total times, and the increase over RGB-only capture.

    Raises
    ------
    SpectwinInputError
        On malformed input, or when no assignment keeps every image within ``image_limit_s``.

    References
    ----------
    The thesis, section 10.4 (band scheduling by bin packing: 30 bands in 8 RGB images at
    about +41 %, 10 images with the noisiest bands twice at about +61 %).

    Examples
    --------
    >>> plan = schedule_bands([3.0, 2.0, 2.0, 1.0], 2, rgb_exposures_s=[4.0])
    >>> plan.images, plan.total_s, plan.increase
    (((0, 3), (1, 2)), 8.0, 0.0)
    """
    instance = _instance(band_exposures_s, rgb_exposures_s, repeat_bands, image_limit_s)
    n = _n_images(n_images, instance)
    limit = _positive_scalar("time_limit_s", time_limit_s)
    schedule, decided = _solve(instance, n, limit)
    if schedule is None and decided:
        raise SpectwinInputError(
            f"n_images: no schedule of {instance.exposures_s.size} band exposures in {n} images "
            f"keeps every image within image_limit_s = {instance.image_limit_s:g} s"
        )
    if schedule is None:
        raise SpectwinInputError(
            f"time_limit_s: the solver found no schedule of {instance.exposures_s.size} band "
            f"exposures in {n} images within {limit:g} s; allow it more time"
        )
    return schedule


def fewest_images(
    band_exposures_s: np.ndarray,
    *,
    rgb_exposures_s: Sequence[float] | np.ndarray = THESIS_RGB_EXPOSURES_S,
    repeat_bands: Sequence[int] = (),
    image_limit_s: float | None = None,
    time_limit_s: float = 10.0,
) -> BandSchedule:
    """The smallest number of RGB images that can hold every band exposure, and its schedule.

    An image may last up to ``image_limit_s``; by default that is the longer of the RGB
    exposure set and the longest band exposure, the shortest duration the image holding that
    band can have. The image count is then the optimum of classic bin packing with that
    capacity; for it, the schedule of least total time is returned (see
    :func:`schedule_bands`).

    Parameters
    ----------
    band_exposures_s, rgb_exposures_s, repeat_bands, time_limit_s
        As for :func:`schedule_bands` (``time_limit_s`` per solver call).
    image_limit_s
        Longest allowed image duration (default
        :math:`\\max(\\sum_i t_i, \\max_\\lambda t_\\lambda)`).

    Returns
    -------
    BandSchedule
        The schedule in the fewest images; ``optimal`` is ``False`` if a solver call stopped at
        its time limit (a smaller count was then not ruled out, or the total not proven
        minimal).

    References
    ----------
    The thesis, section 10.4 ("we would be able to acquire the 30 spectral images during the
    acquisition of 8 RGB images").

    Examples
    --------
    >>> fewest_images([3.0, 2.0, 1.5, 1.0], rgb_exposures_s=[2.5]).images
    ((0,), (1,), (2, 3))
    """
    exposures = _positive_vector("band_exposures_s", band_exposures_s)
    rgb = _positive_vector("rgb_exposures_s", rgb_exposures_s)
    limit = max(rgb.sum(), exposures.max()) if image_limit_s is None else image_limit_s
    instance = _instance(exposures, rgb, repeat_bands, limit)
    solver_limit = _positive_scalar("time_limit_s", time_limit_s)
    copies = 2 if instance.bands.size > exposures.size else 1
    first = max(copies, math.ceil(instance.exposures_s.sum() / instance.image_limit_s - 1e-9))
    proven = True
    for n in range(first, instance.exposures_s.size + 1):
        schedule, decided = _solve(instance, n, solver_limit)
        if schedule is not None:
            return replace(schedule, optimal=proven and decided)
        proven = proven and decided
    raise SpectwinInputError(
        f"time_limit_s: the solver found no schedule within {solver_limit:g} s per call, not "
        "even one image per band exposure; allow it more time"
    )
