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
   here by a deterministic branch and bound search (:func:`schedule_bands`,
   :func:`fewest_images`): the same bands give the same schedule on any machine.
   The thesis reports 30 bands in 8 RGB images at about +41 % total exposure time, and 10 RGB
   images with the noisiest bands taken twice at about +61 %.

References
----------
- The thesis, section 10.4 (exposure times :math:`t_\\lambda`, band scheduling by bin packing,
  the +41 % and +61 % figures) and Figure 10.5 (exposure times and filter sizes,
  :math:`\\sigma` = filter size / 5); Eq. 10.1 (the filtered band term).
- Martello, S., & Toth, P. (1990). Knapsack Problems: Algorithms and Computer Implementations.
  Wiley. Chapter 8 (bin packing; the lower bound :math:`L_2`, section 8.3.1).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from recon.errors import InputError

__all__ = [
    "DEFAULT_NODE_LIMIT",
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

DEFAULT_NODE_LIMIT = 100_000
"""Most nodes the band schedule's branch and bound search visits per call (about a second)."""

FILTER_SIZE_PER_SIGMA = 5.0
"""Filter size over the Gaussian's standard deviation (thesis Figure 10.5: sigma = size / 5)."""


def _positive_vector(name: str, values: object, size: int | None = None) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or array.size == 0 or (size is not None and array.size != size):
        expected = f"({size},)" if size is not None else "a non-empty 1-D array"
        raise InputError(
            f"{name}: expected one value per band, shape {expected}, got shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name}: expected finite values, found NaN or infinity")
    if np.any(array <= 0):
        raise InputError(
            f"{name}: expected positive values, got {array[array <= 0][0]:g} at index "
            f"{int(np.flatnonzero(array <= 0)[0])}"
        )
    return array


def _positive_scalar(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a positive number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a finite, positive number, got {value}")
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
        raise InputError(
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
    0.4 % from 0.8 px on (a kernel truncated at 3 sigma, as in ``recon.spectralize.energy``, adds
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
        raise InputError("sigma_px: expected finite, positive standard deviations in px")
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
        raise InputError(
            f"relative_noise: expected one value per band, a non-empty 1-D array, got shape "
            f"{noise.shape}"
        )
    if not np.all(np.isfinite(noise)) or np.any(noise < 0):
        raise InputError("relative_noise: expected finite, non-negative values per band")
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
        Whether the search proved ``total_s`` minimal (and, from :func:`fewest_images`, the
        image count smallest); ``False`` when it stopped at its node limit.
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
        raise InputError(
            f"repeat_bands: expected distinct band indices in [0, {exposures.size}), got "
            f"{list(repeat_bands)}"
        )
    bands = np.concatenate([np.arange(exposures.size), repeats.astype(np.int64)])
    order = np.argsort(-exposures[bands], kind="stable")
    limit = None if image_limit_s is None else _positive_scalar("image_limit_s", image_limit_s)
    if limit is not None and limit < exposures.max():
        raise InputError(
            f"image_limit_s: {limit:g} s is shorter than the longest band exposure "
            f"({exposures.max():g} s), which must fit into one image"
        )
    return _Instance(exposures[bands][order], bands[order], float(rgb.sum()), limit)


def _n_images(n_images: object, instance: _Instance) -> int:
    if isinstance(n_images, bool) or not isinstance(n_images, (int, np.integer)) or n_images < 1:
        raise InputError(f"n_images: expected a positive integer, got {n_images!r}")
    if np.unique(instance.bands).size < instance.bands.size and n_images < 2:
        raise InputError(
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
                        and loads[image] + shift < loads[longest] * (1 - 1e-9)
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


def _bins_lower_bound(sizes: np.ndarray, capacity: float) -> int:
    """Martello and Toth's bound :math:`L_2` on the number of bins of ``capacity`` that hold
    ``sizes`` (Martello & Toth 1990, section 8.3.1).

    For each :math:`\\alpha \\le C / 2`, items larger than :math:`C - \\alpha` and items in
    :math:`(C / 2, C - \\alpha]` each need a bin of their own; the items in
    :math:`[\\alpha, C / 2]` can use only the room the latter leave and need
    :math:`\\lceil \\cdot / C \\rceil` further bins for the rest.
    """
    tol = 1e-9 * capacity
    half = capacity / 2.0
    best = math.ceil(sizes.sum() / capacity - 1e-9)
    for alpha in np.unique(np.concatenate([[0.0], sizes[sizes <= half + tol]])):
        own = sizes > capacity - alpha + tol
        large = (sizes > half + tol) & ~own
        small = (sizes >= alpha - tol) & (sizes <= half + tol)
        room = large.sum() * capacity - sizes[large].sum()
        extra = math.ceil(max(0.0, sizes[small].sum() - room) / capacity - 1e-9)
        best = max(best, int(own.sum() + large.sum() + extra))
    return best


def _root_bound(t: np.ndarray, rgb_s: float, n: int) -> float:
    """Lower bound on the total of any schedule in ``n`` images.

    Every image lasts at least :math:`R` (the RGB set) and together they hold all band time
    :math:`T`. Bands longer than :math:`R` (:math:`k` of them, summing to :math:`B`) make their
    image outlast the RGB set; relaxing the shorter bands to a divisible fluid, the best is one
    long band per image and the fluid in the other images, so the total is at least
    :math:`\\max(T, n R, B + (n - k) R)`.
    """
    long = t[t > rgb_s]
    return max(float(t.sum()), n * rgb_s, float(long.sum()) + max(0, n - long.size) * rgb_s)


class _NodeLimitReached(Exception):
    pass


class _OptimumReached(Exception):
    pass


def _search(
    instance: _Instance, n: int, start: np.ndarray | None, lower: float, node_limit: int
) -> tuple[np.ndarray | None, bool]:
    """Depth-first branch and bound over the items (longest first), each put into one image.

    The total is :math:`T + \\sum_b \\max(0, R - L_b)`: the band time plus the time images wait
    for the RGB set beyond their bands (their gap). A node's bound lets the items still to place
    close the gaps as a divisible fluid, except that a gap shorter than the shortest item
    costs at least that item to close. Images with the same load and the same repeated bands
    are interchangeable, so only one of them is tried; with an image limit, a node is dropped
    when the room in the images that can still take an item is less than the items left.

    Returns the best assignment found (``start`` if none is better, ``None`` if none exists)
    and whether the search finished within ``node_limit`` nodes, which proves it optimal (or
    proves that no assignment exists). Deterministic: no clock, no randomness.
    """
    t = instance.exposures_s.tolist()
    bands = instance.bands.tolist()
    rgb_s = instance.rgb_s
    capacity = math.inf if instance.image_limit_s is None else instance.image_limit_s
    m = len(t)
    total = float(np.sum(t))
    rest = np.concatenate([np.cumsum(instance.exposures_s[::-1])[::-1], [0.0]]).tolist()
    shortest = t[-1]
    tol = 1e-9 * max(total, n * rgb_s)
    capacity_tol = 1e-9 * capacity if math.isfinite(capacity) else 0.0
    repeated = {b for b in bands if bands.count(b) > 1}

    loads = [0.0] * n
    held: list[set[int]] = [set() for _ in range(n)]
    image_of_item = [0] * m
    best: list[Any] = [None, math.inf]
    if start is not None:
        best = [start.copy(), float(np.maximum(np.bincount(start, t, n), rgb_s).sum())]
    nodes = 0

    def bound(j: int) -> float:
        fluid = rest[j]
        under, live, dead = 0.0, 0.0, []
        for load in loads:
            gap = rgb_s - load
            if gap <= 0:
                continue
            if j == m or capacity - load < shortest - capacity_tol:
                under += gap  # no band fits any more: the gap stays
            elif gap >= shortest:
                live += gap
            else:
                dead.append(gap)
        under += live + sum(dead) - min(fluid, live)
        fluid -= min(fluid, live)
        for gap in sorted(dead, reverse=True):
            if fluid <= 0:
                break
            under -= gap * min(1.0, fluid / shortest)
            fluid -= shortest
        return total + under

    def visit(j: int) -> None:
        nonlocal nodes
        nodes += 1
        if nodes > node_limit:
            raise _NodeLimitReached
        if bound(j) >= best[1] - tol:
            return
        if j == m:
            best[0], best[1] = np.array(image_of_item), bound(j)
            if best[1] <= lower + tol:
                raise _OptimumReached
            return
        if math.isfinite(capacity):
            room = sum(
                capacity - load for load in loads if capacity - load >= shortest - capacity_tol
            )
            if room < rest[j] - capacity_tol:
                return
        size, band = t[j], bands[j]
        seen = set()
        children = []
        for image in range(n):
            load = loads[image]
            if load + size > capacity + capacity_tol or band in held[image]:
                continue
            key = (round(load, 9), frozenset(held[image]))
            if key in seen:
                continue
            seen.add(key)
            gap = rgb_s - load
            if gap >= size - tol:
                order = (0, gap)  # fits within the RGB set: best fit
            elif gap > 0:
                order = (1, size - gap)  # closes the gap: least overhang first
            else:
                order = (2, load)  # image already spectral-bound: least loaded first
            children.append((order, image))
        for _, image in sorted(children):
            loads[image] += size
            if band in repeated:
                held[image].add(band)
            image_of_item[j] = image
            visit(j + 1)
            loads[image] -= size
            held[image].discard(band)

    try:
        visit(0)
    except _NodeLimitReached:
        return best[0], False
    except _OptimumReached:
        pass
    return best[0], True


def _greedy(instance: _Instance, n: int, fullest: bool) -> np.ndarray | None:
    """Longest bands first, each into the least loaded image that can take it, or (``fullest``,
    best fit) into the fullest; ``None`` if a band fits nowhere."""
    t, bands = instance.exposures_s, instance.bands
    capacity = math.inf if instance.image_limit_s is None else instance.image_limit_s
    loads = np.zeros(n)
    image_of_item = np.empty(t.size, dtype=np.int64)
    for j in range(t.size):
        fits = (loads + t[j] <= capacity * (1 + 1e-9)) & np.array(
            [bands[j] not in bands[:j][image_of_item[:j] == b] for b in range(n)]
        )
        if not fits.any():
            return None
        candidates = np.flatnonzero(fits)
        pick = np.argmax if fullest else np.argmin
        image = int(candidates[pick(loads[fits])])
        image_of_item[j] = image
        loads[image] += t[j]
    return image_of_item


def _improve(instance: _Instance, image_of_item: np.ndarray, n: int) -> np.ndarray:
    """Move one band to another image, or swap two bands between images, while that shortens
    the total (the first such step in a fixed order, repeated)."""
    t, bands, rgb_s = instance.exposures_s, instance.bands, instance.rgb_s
    capacity = math.inf if instance.image_limit_s is None else instance.image_limit_s * (1 + 1e-9)
    tol = 1e-9 * max(float(t.sum()), n * rgb_s)
    items = np.arange(t.size)
    image_of_item = image_of_item.copy()
    loads = np.bincount(image_of_item, weights=t, minlength=n)

    def gain(source: int, target: int, shift: float) -> float:
        """Total saved by moving ``shift`` of band time from ``source`` to ``target``."""
        return (
            max(rgb_s, loads[source])
            + max(rgb_s, loads[target])
            - max(rgb_s, loads[source] - shift)
            - max(rgb_s, loads[target] + shift)
        )

    def free_of(band: int, image: int, leaving: int) -> bool:
        return band not in bands[(image_of_item == image) & (items != leaving)]

    def step() -> bool:
        for a in range(items.size):
            source = image_of_item[a]
            for target in range(n):
                if target == source:
                    continue
                for c in (-1, *items[image_of_item == target].tolist()):
                    shift = t[a] - (t[c] if c >= 0 else 0.0)
                    if (
                        gain(source, target, shift) > tol
                        and loads[target] + shift <= capacity
                        and loads[source] - shift <= capacity
                        and free_of(bands[a], target, c)
                        and (c < 0 or free_of(bands[c], source, a))
                    ):
                        image_of_item[a] = target
                        if c >= 0:
                            image_of_item[c] = source
                        loads[source] -= shift
                        loads[target] += shift
                        return True
        return False

    while step():
        pass
    return image_of_item


def _solve(instance: _Instance, n: int, node_limit: int) -> tuple[BandSchedule | None, bool]:
    """Minimum-total assignment of the instance's items to ``n`` images, and whether the search
    decided the problem (proved the optimum or that no assignment exists) within its node limit.

    A longest-first greedy schedule is kept when it reaches :func:`_root_bound`; with an image
    limit, :func:`_bins_lower_bound` rules out too few images at once; otherwise
    :func:`_search` improves on the greedy schedule until it proves the optimum. The solution
    is then balanced by :func:`_balance`.
    """
    t, rgb_s = instance.exposures_s, instance.rgb_s
    if instance.image_limit_s is not None and _bins_lower_bound(t, instance.image_limit_s) > n:
        return None, True

    def total(image_of_item: np.ndarray) -> float:
        return float(np.maximum(np.bincount(image_of_item, t, n), rgb_s).sum())

    greedy = [_greedy(instance, n, fullest) for fullest in (False, True)]
    starts = [_improve(instance, start, n) for start in greedy if start is not None]
    image_of_item = min(starts, key=total) if starts else None
    lower = _root_bound(t, rgb_s, n)
    tol = 1e-9 * max(float(t.sum()), n * rgb_s)
    if image_of_item is not None and total(image_of_item) <= lower + tol:
        decided = True
    else:
        image_of_item, decided = _search(instance, n, image_of_item, lower, node_limit)
        if image_of_item is not None and not decided:
            image_of_item = _improve(instance, image_of_item, n)
            decided = total(image_of_item) <= lower + tol
    if image_of_item is None:
        return None, decided
    image_of_item = _balance(instance, image_of_item, n)
    spectral = np.bincount(image_of_item, weights=t, minlength=n)
    image_s = np.maximum(spectral, rgb_s)
    total_s = float(image_s.sum())
    schedule = BandSchedule(
        images=tuple(
            tuple(sorted(int(b) for b in instance.bands[image_of_item == image]))
            for image in range(n)
        ),
        spectral_s=spectral,
        image_s=image_s,
        rgb_s=rgb_s,
        total_s=total_s,
        increase=total_s / (n * rgb_s) - 1.0,
        optimal=decided,
    )
    return schedule, decided


def _node_limit(node_limit: object) -> int:
    if (
        isinstance(node_limit, bool)
        or not isinstance(node_limit, (int, np.integer))
        or node_limit < 1
    ):
        raise InputError(f"node_limit: expected a positive integer, got {node_limit!r}")
    return int(node_limit)


def schedule_bands(
    band_exposures_s: np.ndarray,
    n_images: int,
    *,
    rgb_exposures_s: Sequence[float] | np.ndarray = THESIS_RGB_EXPOSURES_S,
    repeat_bands: Sequence[int] = (),
    image_limit_s: float | None = None,
    node_limit: int = DEFAULT_NODE_LIMIT,
) -> BandSchedule:
    """Assign every band exposure to one of ``n_images`` RGB images, minimizing total time.

    The spectral camera exposes in parallel to the RGB cameras, and a band exposure is finished
    during one image (one light source); an image therefore lasts
    :math:`\\max(\\sum_i t_i, \\sum_{\\lambda \\in image} t_\\lambda)`. The assignment that
    minimizes the sum of image durations is a bin-packing problem, solved exactly: a
    longest-first greedy schedule, improved by moving and swapping bands, is proven optimal by a
    lower bound on the total, or else a branch and bound search over the bands improves it
    until it proves the optimum. Bands with a wide spread of exposure times, as in the thesis,
    are decided in milliseconds. Among equally short schedules the search's pick can be
    lopsided; bands are then moved or swapped out of the longest image while that shortens it
    without lengthening the total. Proving the optimum is hardest when the band exposures sum to
    about ``n_images`` RGB sets (a tight bin packing): there ``node_limit`` may end the search.
    The search is deterministic: the same input gives the same schedule on any machine, at any
    load.

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
    node_limit
        Most nodes the branch and bound search visits (about a second of search); if it is
        reached the best schedule found is returned with ``optimal=False``.

    Returns
    -------
    BandSchedule
        The assignment, per-image and total times, and the increase over RGB-only capture.

    Raises
    ------
    InputError
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
    limit = _node_limit(node_limit)
    schedule, decided = _solve(instance, n, limit)
    if schedule is None and decided:
        raise InputError(
            f"n_images: no schedule of {instance.exposures_s.size} band exposures in {n} images "
            f"keeps every image within image_limit_s = {instance.image_limit_s:g} s"
        )
    if schedule is None:
        raise InputError(
            f"node_limit: the search found no schedule of {instance.exposures_s.size} band "
            f"exposures in {n} images within {limit} nodes; allow it more nodes"
        )
    return schedule


def fewest_images(
    band_exposures_s: np.ndarray,
    *,
    rgb_exposures_s: Sequence[float] | np.ndarray = THESIS_RGB_EXPOSURES_S,
    repeat_bands: Sequence[int] = (),
    image_limit_s: float | None = None,
    node_limit: int = DEFAULT_NODE_LIMIT,
) -> BandSchedule:
    """The smallest number of RGB images that can hold every band exposure, and its schedule.

    An image may last up to ``image_limit_s``; by default that is the longer of the RGB
    exposure set and the longest band exposure, the shortest duration the image holding that
    band can have. The image count is then the optimum of classic bin packing with that
    capacity (counts below Martello and Toth's bound :math:`L_2` are ruled out at once); for
    it, the schedule of least total time is returned (see :func:`schedule_bands`).

    Parameters
    ----------
    band_exposures_s, rgb_exposures_s, repeat_bands, node_limit
        As for :func:`schedule_bands` (``node_limit`` per image count tried).
    image_limit_s
        Longest allowed image duration (default
        :math:`\\max(\\sum_i t_i, \\max_\\lambda t_\\lambda)`).

    Returns
    -------
    BandSchedule
        The schedule in the fewest images; ``optimal`` is ``False`` if a search stopped at its
        node limit (a smaller count was then not ruled out, or the total not proven minimal).

    References
    ----------
    The thesis, section 10.4 ("we would be able to acquire the 30 spectral images during the
    acquisition of 8 RGB images"). Martello & Toth (1990), section 8.3.1 (the bound
    :math:`L_2`).

    Examples
    --------
    >>> fewest_images([3.0, 2.0, 1.5, 1.0], rgb_exposures_s=[2.5]).images
    ((0,), (1,), (2, 3))
    """
    exposures = _positive_vector("band_exposures_s", band_exposures_s)
    rgb = _positive_vector("rgb_exposures_s", rgb_exposures_s)
    limit = max(rgb.sum(), exposures.max()) if image_limit_s is None else image_limit_s
    instance = _instance(exposures, rgb, repeat_bands, limit)
    nodes = _node_limit(node_limit)
    copies = 2 if instance.bands.size > exposures.size else 1
    first = max(copies, _bins_lower_bound(instance.exposures_s, float(limit)))
    proven = True
    for n in range(first, instance.exposures_s.size + 1):
        schedule, decided = _solve(instance, n, nodes)
        if schedule is not None:
            return replace(schedule, optimal=proven and decided)
        proven = proven and decided
    raise InputError(
        f"node_limit: the search found no schedule within {nodes} nodes per image count, not "
        "even one image per band exposure; allow it more nodes"
    )
