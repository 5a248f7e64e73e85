"""Camera response curves from exposure series: Robertson et al. (2003) and its filtered variant.

The imaging model of the thesis (section 3.3, Eq. 3.1) is :math:`p_x = f^{-1}(t I_x) + d_x`: the
pixel value is the camera's response to the exposure :math:`t I_x` plus the dark signal. Its
radiometric calibration recovers the *inverse* response :math:`f` (the thesis's
:math:`\\hat f^{-1}`; "energy" for its values) up to one scale factor, from a series of
photographs of a static scene at several exposure times, with the algorithm of Robertson et al.
(2003). It alternates two weighted least-squares steps on
:math:`O = \\sum_{ij} w(y_{ij}) (f(y_{ij}) - t_i x_j)^2`:

1. irradiance (Robertson Eq. 7, thesis Eq. 10.3):
   :math:`x_j = \\sum_i w(y_{ij}) t_i f(y_{ij}) / \\sum_i w(y_{ij}) t_i^2`;
2. response (Robertson Eq. 11): :math:`f(m) = \\frac{1}{|E_m|} \\sum_{(i,j) \\in E_m} t_i x_j`
   with :math:`E_m = \\{(i, j) : y_{ij} = m\\}`, then :math:`f` is divided by its value at a
   reference level (Robertson fix :math:`f(128) = 1` for 8-bit data; here the middle level).

Both steps are sums over samples grouped by pixel value: ``numpy.bincount`` makes one iteration
cost a few passes over the samples whatever the number of levels (4096 for 12-bit data, 65536
for 16-bit).

For underexposed, low-SNR images the thesis (section 10.3) applies the algorithm to dark-subtracted
frames after a Gaussian filter (Eq. 10.4), so pixel values become fractional: :math:`f` is stored
at integral values and interpolated linearly (Eq. 10.5), and the response step splits each sample
between the two integral values around it (Eq. 10.6-10.8). :func:`robertson_filtered` implements
that; with ``sigma_px=0`` and integral values it reduces to :func:`robertson`.

Choose exposure times whose ratios are not all integer powers of one ratio (not 1, 2, 4, 8, ...
alone). Otherwise any log-periodic modulation of :math:`f` with that ratio as period fits the
data equally well (the self-similar ambiguity of Grossberg and Nayar, 2003): the iteration then
drifts slowly along that family instead of converging (measured here on a noise-free 8-bit
series with exposures 0.25, 0.5, ..., 8: the curve's relative spread against the truth wanders
between 0.4 % and 1.1 % over 3000 iterations, while with the ratios made irregular it settles at
0.13 % within about 50 iterations). The functions warn about such series.

References
----------
- Robertson, M. A., Borman, S., & Stevenson, R. L. (2003). Estimation-theoretic approach to
  dynamic range enhancement using multiple exposures. Journal of Electronic Imaging, 12(2),
  219-228. doi:10.1117/1.1557695 (Eq. 7 and Eq. 11; Gaussian-like weighting).
- Grossberg, M. D., & Nayar, S. K. (2003). Determining the camera response from images: what is
  knowable? IEEE Transactions on Pattern Analysis and Machine Intelligence, 25(11), 1455-1467.
  doi:10.1109/TPAMI.2003.1240119 (the ambiguity with exposure ratios that are powers of one).
- The thesis: section 3.3 (Eq. 3.1-3.2, calibration with Robertson's algorithm from a dark-
  subtracted series), section 10.3 (Eq. 10.3-10.8, the filtered variant; Fig. 10.3), Fig. 10.5
  (Gaussian :math:`\\sigma` = 1/5 of the filter size).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from scipy import ndimage

from recon.errors import InputError
from recon.radiometric.hdr import (
    exposure_times,
    frame_stack,
    interpolate_curve,
    response_weights,
)

__all__ = [
    "FILTER_TRUNCATE",
    "clipped_after_filter",
    "filter_frames",
    "robertson",
    "robertson_filtered",
]

FILTER_TRUNCATE = 2.5
"""Gaussian kernel radius in standard deviations: the thesis sets :math:`\\sigma` to 1/5 of the
filter size (Fig. 10.5 caption), i.e. a kernel of about :math:`2 \\times 2.5 \\sigma` pixels."""

_MAX_BIT_DEPTH = 24


def _bit_depth(bit_depth: object, values: np.ndarray) -> int:
    if bit_depth is None:
        if values.dtype == np.uint8:
            return 8
        raise InputError(
            f"bit_depth: expected the bit depth of the camera's values (e.g. 12) for frames of "
            f"dtype {values.dtype}; only uint8 frames imply it"
        )
    if (
        isinstance(bit_depth, bool)
        or not isinstance(bit_depth, (int, np.integer))
        or not 2 <= bit_depth <= _MAX_BIT_DEPTH
    ):
        raise InputError(
            f"bit_depth: expected an integer from 2 to {_MAX_BIT_DEPTH}, got {bit_depth!r}"
        )
    return int(bit_depth)


def _iteration_options(max_iterations: object, tolerance: object) -> tuple[int, float]:
    if (
        isinstance(max_iterations, bool)
        or not isinstance(max_iterations, (int, np.integer))
        or max_iterations < 1
    ):
        raise InputError(f"max_iterations: expected a positive integer, got {max_iterations!r}")
    if not isinstance(tolerance, (int, float)) or not np.isfinite(tolerance) or tolerance <= 0:
        raise InputError(f"tolerance: expected a positive number, got {tolerance!r}")
    return int(max_iterations), float(tolerance)


def _check_distinct(times: np.ndarray) -> None:
    distinct = np.unique(times)
    if distinct.size < 2:
        raise InputError(f"exposure_s: expected at least 2 different exposure times, got {times}")
    steps = np.log(distinct / distinct[0])
    multiples = steps / steps[1]
    if np.all(np.abs(multiples - np.round(multiples)) < 0.02):
        warnings.warn(
            f"exposure_s: all exposure ratios are integer powers of {distinct[1] / distinct[0]:.4g}"
            "; the response is then only known up to a log-periodic modulation (Grossberg and "
            "Nayar 2003) and the iteration may drift; add an exposure time off that ladder",
            RuntimeWarning,
            stacklevel=3,
        )


def _sigma(sigma_px: object) -> float:
    if isinstance(sigma_px, bool) or not isinstance(sigma_px, (int, float, np.floating)):
        raise InputError(f"sigma_px: expected a number of pixels >= 0, got {sigma_px!r}")
    if not np.isfinite(sigma_px) or sigma_px < 0:
        raise InputError(f"sigma_px: expected a number of pixels >= 0, got {sigma_px}")
    return float(sigma_px)


def _clip_limits(clip_limits: Any, levels: int | None) -> tuple[float, float]:
    """``(low, high)`` as floats, low < high; ``None`` means ``(0, levels - 1)``."""
    if clip_limits is None and levels is not None:
        return 0.0, float(levels - 1)
    try:
        low, high = (float(limit) for limit in clip_limits)
    except (TypeError, ValueError) as error:
        raise InputError(
            f"clip_limits: expected (low, high) raw values, got {clip_limits!r}"
        ) from error
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise InputError(
            f"clip_limits: expected finite raw values with low < high, got {clip_limits!r}"
        )
    return low, high


def _clipped(values: np.ndarray, limits: tuple[float, float]) -> np.ndarray:
    return (values <= limits[0]) | (values >= limits[1])


def _image_axes(values: np.ndarray) -> tuple[int, int]:
    if values.ndim < 3:
        raise InputError(
            f"frames: expected images (n_exposures, ..., H, W) to filter, got shape {values.shape}"
        )
    return values.ndim - 2, values.ndim - 1


# -- the Robertson iteration on flat samples --------------------------------------------------


def _recover(
    values: np.ndarray,
    times: np.ndarray,
    table: np.ndarray,
    valid: np.ndarray,
    offset: float,
    reference_level: int | None,
    max_iterations: int,
    tolerance: float,
    multiplicity: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Robertson's iteration on ``(n_exposures, n_pixels)`` values; Eq. 10.5-10.8 if fractional.

    ``valid`` marks the samples that take part; ``multiplicity`` ``(n_pixels,)`` counts how many
    identical pixels a column stands for. Returns the curve ``(levels,)`` (NaN outside the
    observed values) and ``x`` ``(n_pixels,)``.
    """
    levels = table.size
    top = levels - 1
    t = times[:, None]
    inside = valid & (values >= 0) & (values <= top)
    if values.dtype.kind in "iu":
        low = np.where(inside, values, 0).astype(np.intp)
        high, fraction = low, None
        weights = np.where(inside, table[low], 0.0)
    else:
        clipped = np.where(inside, values, 0.0)
        low = np.minimum(np.floor(clipped).astype(np.intp), top)
        fraction = clipped - low
        high = np.minimum(low + (fraction > 0), top)
        weights = np.where(inside, interpolate_curve(table, clipped), 0.0)
    weighted_t = weights * t
    denominator = np.sum(weighted_t * t, axis=0)
    # Pixels with no weighted sample have no irradiance (Eq. 10.3's denominator is zero) and
    # take no part in the response step.
    has_weight = denominator > 0
    take = inside & has_weight[None, :]
    count = take.astype(np.float64)
    if multiplicity is not None:
        count *= multiplicity[None, :]
    low_flat, high_flat = low.ravel(), high.ravel()
    if fraction is None:
        left_weight, right_weight = count.ravel(), None
    else:
        # Eq. 10.6-10.7: a sample belongs to L(floor) with weight 1 - delta and to R(ceil)
        # with weight delta.
        left_weight = (count * (1.0 - fraction)).ravel()
        right_weight = (count * fraction).ravel()
    left_total = np.bincount(low_flat, weights=left_weight, minlength=levels)
    right_total = (
        np.bincount(high_flat, weights=right_weight, minlength=levels)
        if right_weight is not None
        else np.zeros(levels)
    )
    observed = (left_total > 0) | (right_total > 0)
    if np.count_nonzero(observed) < 2:
        raise InputError(
            "frames: expected samples at 2 or more pixel values within [0, levels - 1] in "
            "pixels with a usable (non-clipped) exposure"
        )
    observed_levels = np.flatnonzero(observed)
    first, last = observed_levels[0], observed_levels[-1]
    if reference_level is None:
        reference = levels // 2
        if not first <= reference <= last:
            reference = int(np.round(np.median(values[take])))
    else:
        if (
            isinstance(reference_level, bool)
            or not isinstance(reference_level, (int, np.integer))
            or not first <= reference_level <= last
        ):
            raise InputError(
                f"reference_level: expected an integral pixel value within the observed range "
                f"[{first}, {last}], got {reference_level!r}"
            )
        reference = int(reference_level)
    if reference - offset == 0:
        raise InputError(
            f"reference_level: {reference} equals the offset {offset}, where the response is zero"
        )
    all_levels = np.arange(levels, dtype=np.float64)

    def irradiance(curve: np.ndarray) -> np.ndarray:
        """Eq. 10.3 / 10.5 with the curve completed over all levels (no NaN)."""
        if fraction is None:
            energies = curve[low]
        else:
            energies = curve[low] * (1.0 - fraction) + curve[high] * fraction
        numerator = np.sum(weighted_t * energies, axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(has_weight, numerator / denominator, np.nan)

    # Start from a linear response through the offset (Robertson et al. start linear too).
    curve = (all_levels - offset) / (reference - offset)
    converged = False
    for _ in range(max_iterations):
        x = np.where(has_weight, irradiance(curve), 0.0)
        energy = (t * x[None, :]).ravel()
        with np.errstate(invalid="ignore", divide="ignore"):
            # np.ndarray: NumPy's stub types bincount as integer, also with float weights
            left: np.ndarray = np.bincount(low_flat, weights=left_weight * energy, minlength=levels)
            left /= left_total
            if right_weight is None:
                update = left  # Robertson Eq. 11: the mean of t_i x_j over E_m.
            else:
                right: np.ndarray = np.bincount(
                    high_flat, weights=right_weight * energy, minlength=levels
                )
                right /= right_total
                # Eq. 10.8: the mean of the two weighted means; where one side is empty (e.g.
                # integral values, delta = 0) the other side alone.
                update = np.where(
                    (left_total > 0) & (right_total > 0),
                    0.5 * (left + right),
                    np.where(left_total > 0, left, right),
                )
        # Unobserved levels: linear interpolation (constant beyond the observed range).
        update = np.interp(all_levels, observed_levels, update[observed_levels])
        scale = update[reference]
        if not np.isfinite(scale) or scale == 0:
            raise InputError(
                f"reference_level: the response at {reference} came out {scale}; choose a level "
                "with a non-zero response"
            )
        update /= scale
        change = np.max(np.abs(update - curve)[observed]) / np.max(np.abs(update[observed]))
        curve = update
        if change < tolerance:
            converged = True
            break
    if not converged:
        warnings.warn(
            f"Robertson's iteration did not converge to tolerance {tolerance} within "
            f"{max_iterations} iterations",
            RuntimeWarning,
            stacklevel=3,
        )
    x = irradiance(curve)
    result = curve.copy()
    result[:first] = np.nan
    result[last + 1 :] = np.nan
    return result, x


# -- public functions ------------------------------------------------------------------------


def robertson(
    frames: np.ndarray,
    exposure_s: np.ndarray,
    *,
    bit_depth: int | None = None,
    weighting: str | np.ndarray = "gaussian",
    clip_limits: tuple[float, float] | None = None,
    reference_level: int | None = None,
    max_iterations: int = 200,
    tolerance: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse response and irradiance from an exposure series (Robertson et al. 2003).

    Alternates the irradiance estimate (Robertson Eq. 7, thesis Eq. 10.3) and the response
    estimate (Robertson Eq. 11) until the curve changes by less than ``tolerance`` (relative to
    its largest value); see the module description. The scene must be static and the camera
    settings other than the exposure time fixed. As in the thesis (section 3.3) the frames may be
    dark-subtracted first; without that the curve absorbs the mean dark level (ADC offset).

    Parameters
    ----------
    frames
        ``(n_exposures, ...)`` integer pixel values; the trailing axes are pixels (one image
        ``(H, W)``, or several scenes ``(n_scenes, H, W)`` shot with the same exposure times).
    exposure_s
        ``(n_exposures,)`` exposure times in seconds, at least two of them different.
    bit_depth
        The camera's bit depth: values lie in ``[0, 2**bit_depth - 1]``. Implied (8) for uint8
        frames, required otherwise.
    weighting
        :math:`w(m)`, see :func:`recon.radiometric.hdr.response_weights`; the default is Robertson's
        Gaussian-like weighting with weight zero at 0 and at saturation.
    clip_limits
        ``(low, high)``: values at or below ``low`` or at or above ``high`` are censored (they
        only say that the exposure lies beyond the range) and take no part in either step.
        Default ``(0, 2**bit_depth - 1)``. Set ``high`` a few noise widths below the ADC's top
        when the full well saturates first and read noise spreads the clipped values: even a
        small weight on them is multiplied by :math:`t_i^2` in Eq. 10.3.
    reference_level
        The level where the curve is 1 (Robertson: 128 of 256); default the middle level, or
        the median observed value when the middle level is not observed.
    max_iterations, tolerance
        Stopping rule; a ``RuntimeWarning`` tells when ``max_iterations`` was reached first.

    Returns
    -------
    inverse_response : numpy.ndarray
        ``(2**bit_depth,)`` float64 :math:`f(m)`, relative exposure per pixel value, 1 at the
        reference level; levels between observed ones are interpolated linearly, levels below
        the smallest or above the largest observed value are NaN. The values at levels with
        weight zero (0, saturation) are the mean exposure of their clipped samples and carry
        no calibration.
    irradiance : numpy.ndarray
        ``frames.shape[1:]`` float64 :math:`x_j` in curve units per second (NaN for pixels
        clipped in every exposure).

    References
    ----------
    Robertson et al. (2003), J. Electronic Imaging 12(2), Eq. 7 and Eq. 11; the thesis,
    section 3.3 and Eq. 10.3.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> irradiance = np.exp(rng.uniform(0.0, 5.0, 4000))
    >>> times = np.array([0.25, 0.45, 1.0, 1.7, 4.1, 8.0])  # ratios off a power ladder
    >>> exposures = times[:, None] * irradiance
    >>> frames = np.clip(np.round(255 * (exposures / 300) ** 0.5), 0, 255).astype(np.uint8)
    >>> curve, x = robertson(frames, times)
    >>> truth = (np.arange(256) / 255) ** 2
    >>> ratio = curve[60:240] / truth[60:240]
    >>> bool(np.std(ratio) / np.mean(ratio) < 0.02)
    True
    """
    values = frame_stack(frames)
    if values.dtype.kind not in "iu":
        raise InputError(
            f"frames: expected integer pixel values, got dtype {values.dtype}; use "
            "robertson_filtered for dark-subtracted or filtered (fractional) values"
        )
    times = exposure_times(exposure_s, values.shape[0])
    _check_distinct(times)
    bits = _bit_depth(bit_depth, values)
    levels = 2**bits
    low, high = int(values.min()), int(values.max())
    if low < 0 or high > levels - 1:
        raise InputError(
            f"frames: expected values in [0, {levels - 1}] for bit_depth {bits}, got "
            f"[{low}, {high}]"
        )
    iterations, tol = _iteration_options(max_iterations, tolerance)
    table = response_weights(levels, weighting=weighting)
    flat = values.reshape(values.shape[0], -1)
    # Pixels with the same values in every exposure have the same irradiance: solve for each
    # distinct column once, counted by its multiplicity (exact; large savings on 8-bit data).
    columns, inverse, multiplicity = np.unique(
        flat.T, axis=0, return_inverse=True, return_counts=True
    )
    distinct = np.ascontiguousarray(columns.T).astype(np.intp)
    valid = ~_clipped(distinct, _clip_limits(clip_limits, levels))
    curve, x = _recover(
        distinct,
        times,
        table,
        valid,
        0.0,
        reference_level,
        iterations,
        tol,
        multiplicity.astype(np.float64),
    )
    return curve, x[inverse.ravel()].reshape(values.shape[1:])


def filter_frames(
    frames: np.ndarray,
    *,
    sigma_px: float,
    dark: np.ndarray | None = None,
    offset: float = 0.0,
) -> np.ndarray:
    """Dark-subtracted, Gaussian-filtered frames :math:`\\tilde y_{ij}` (thesis Eq. 10.4).

    :math:`\\tilde y_{ij} = \\sum_p F^j_p [y_{ip} - D_p]` plus ``offset``: the Gaussian kernel
    :math:`F^j` centred at pixel :math:`j` (standard deviation ``sigma_px``, radius
    :data:`FILTER_TRUNCATE` standard deviations, image borders mirrored) is applied to the two
    last axes. Negative values after dark subtraction are kept (thesis Fig. 10.3: clipping them
    would bias the result); ``offset`` shifts them onto the curve's index range, as the thesis
    offsets its dark-subtracted images by 30.

    Parameters
    ----------
    frames
        ``(n_exposures, ..., H, W)`` raw pixel values.
    sigma_px
        Standard deviation of the Gaussian in pixels; 0 leaves the frames unfiltered.
    dark
        The dark values :math:`D`, broadcastable to the frames: one frame ``(H, W)`` or one per
        exposure ``(n_exposures, ..., H, W)`` (see :mod:`recon.radiometric.dark_frames`). Default
        none.
    offset
        Added after filtering.

    Returns
    -------
    numpy.ndarray
        Float64 of the frames' shape.

    References
    ----------
    The thesis, Eq. 10.4, Fig. 10.3 and Fig. 10.5.

    Examples
    --------
    >>> frames = np.zeros((2, 5, 5)); frames[:, 2, 2] = 25.0
    >>> filtered = filter_frames(frames, sigma_px=1.0, offset=30.0)
    >>> round(float(filtered[0].sum() - 30 * 25), 6)
    25.0
    """
    values = frame_stack(frames).astype(np.float64)
    axes = _image_axes(values)
    sigma = _sigma(sigma_px)
    if not isinstance(offset, (int, float, np.number)) or not np.isfinite(offset):
        raise InputError(f"offset: expected a finite number, got {offset!r}")
    if dark is not None:
        dark_values = np.asarray(dark, dtype=np.float64)
        try:
            np.broadcast_shapes(dark_values.shape, values.shape)
        except ValueError as error:
            raise InputError(
                f"dark: expected a shape broadcastable to the frames' {values.shape}, e.g. "
                f"{values.shape[-2:]}, got {dark_values.shape}"
            ) from error
        if np.broadcast_shapes(dark_values.shape, values.shape) != values.shape:
            raise InputError(
                f"dark: shape {dark_values.shape} would enlarge the frames {values.shape}"
            )
        if not np.all(np.isfinite(dark_values)):
            raise InputError("dark: expected finite values, found NaN or infinity")
        values = values - dark_values
    if sigma > 0:
        sigmas = [0.0] * values.ndim
        for axis in axes:
            sigmas[axis] = sigma
        values = ndimage.gaussian_filter(
            values, sigma=sigmas, mode="reflect", truncate=FILTER_TRUNCATE
        )
    return values + float(offset)


def clipped_after_filter(
    frames: np.ndarray, *, sigma_px: float, clip_limits: tuple[float, float]
) -> np.ndarray:
    """Where a filtered value (Eq. 10.4) includes a clipped raw value.

    A raw value at or below ``clip_limits[0]`` (the ADC's floor) or at or above
    ``clip_limits[1]`` (saturation) tells only that the exposure lies beyond the range; a
    filtered pixel whose kernel covers one is censored too.

    Parameters
    ----------
    frames
        ``(n_exposures, ..., H, W)`` raw pixel values.
    sigma_px
        The filter's standard deviation (the kernel reaches :data:`FILTER_TRUNCATE` of them).
    clip_limits
        ``(low, high)`` raw values that count as clipped.

    Returns
    -------
    numpy.ndarray
        Boolean of the frames' shape, True where the filtered value is censored.

    Examples
    --------
    >>> frames = np.zeros((2, 1, 5)) + 10; frames[0, 0, 0] = 255
    >>> clipped_after_filter(frames, sigma_px=0.8, clip_limits=(0, 255))[0, 0].tolist()
    [True, True, True, False, False]
    """
    values = frame_stack(frames)
    axes = _image_axes(values)
    sigma = _sigma(sigma_px)
    clipped = _clipped(values, _clip_limits(clip_limits, None))
    radius = int(FILTER_TRUNCATE * sigma + 0.5)
    if radius == 0:
        return clipped
    size = [1] * values.ndim
    for axis in axes:
        size[axis] = 2 * radius + 1
    return ndimage.maximum_filter(clipped, size=size, mode="reflect")


def robertson_filtered(
    frames: np.ndarray,
    exposure_s: np.ndarray,
    *,
    sigma_px: float,
    dark: np.ndarray | None = None,
    offset: float = 0.0,
    bit_depth: int | None = None,
    weighting: str | np.ndarray = "gaussian",
    clip_limits: tuple[float, float] | None = None,
    reference_level: int | None = None,
    max_iterations: int = 200,
    tolerance: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray]:
    """Robertson's algorithm on dark-subtracted, filtered frames (thesis Eq. 10.4-10.8).

    For calibration in the low-SNR range (thesis section 10.3): the frames are dark-subtracted and
    filtered with a Gaussian (Eq. 10.4, :func:`filter_frames`), which makes the pixel values
    :math:`\\tilde y_{ij}` fractional. The irradiance step (Eq. 10.5) evaluates :math:`f` and
    :math:`w` by linear interpolation between integral values; the response step (Eq. 10.6-10.8)
    computes, with :math:`\\delta_{ij} = \\tilde y_{ij} - \\lfloor \\tilde y_{ij} \\rfloor`,
    :math:`L(m) = \\{(i,j): \\lfloor \\tilde y_{ij} \\rfloor = m\\}` and
    :math:`R(m) = \\{(i,j): \\lceil \\tilde y_{ij} \\rceil = m\\}`,

    .. math::

        f(m) = \\frac{\\sum_{L(m)} (1-\\delta_{ij}) t_i \\tilde x_j}
                    {2 \\sum_{L(m)} (1-\\delta_{ij})}
             + \\frac{\\sum_{R(m)} \\delta_{ij} t_i \\tilde x_j}{2 \\sum_{R(m)} \\delta_{ij}}.

    Where one of the two sums of weights is zero (a level reached from one side only, or
    integral values with :math:`\\delta = 0`) Eq. 10.8 is 0/0 in that half; the other half alone is
    used, which for unfiltered integral frames gives Robertson's Eq. 11 exactly. Eq. 10.8 gives
    each half the same weight however few samples reach a level from that side; it is meant for
    filtered frames, whose fractions are spread evenly. On unfiltered integral frames minus a
    fractional dark frame (a handful of hot pixels) those few samples decide half of their
    levels' values: on the llanos2019 frames :math:`f(224)` came out 1.08 instead of 2.07. There
    use :func:`robertson` on the raw values and subtract the dark frames before merging.

    Parameters
    ----------
    frames
        ``(n_exposures, ..., H, W)`` raw pixel values (integer or float).
    exposure_s
        ``(n_exposures,)`` exposure times in seconds, at least two different.
    sigma_px
        Standard deviation of the Gaussian filter in pixels (thesis Fig. 10.5: 1/5 of the
        filter size); 0 for no filter.
    dark
        Dark values :math:`D` (see :func:`filter_frames`), e.g. averaged dark frames
        interpolated to each exposure time (:func:`recon.radiometric.dark_frames.dark_frames_at`).
    offset
        Added to the filtered, dark-subtracted values so that the negative ones land on the
        curve's index range (the thesis uses 30). ``inverse_response[m]`` belongs to the
        dark-subtracted value ``m - offset``.
    bit_depth
        The curve has ``2**bit_depth`` levels; implied (8) for uint8 frames.
    weighting
        :math:`w`, see :func:`recon.radiometric.hdr.response_weights`, interpolated at fractional
        values.
    clip_limits
        ``(low, high)`` raw values counting as clipped, default ``(0, 2**bit_depth - 1)``;
        filtered values whose kernel covers one are left out (:func:`clipped_after_filter`).
        Values that land outside ``[0, 2**bit_depth - 1]`` after the offset are left out too.
    reference_level, max_iterations, tolerance
        As in :func:`robertson`.

    Returns
    -------
    inverse_response : numpy.ndarray
        ``(2**bit_depth,)`` :math:`f` at the integral values of :math:`\\tilde y + offset`, 1 at
        the reference level, NaN outside the observed range.
    irradiance : numpy.ndarray
        ``frames.shape[1:]`` :math:`\\tilde x_j` of the filtered images (Eq. 10.5).

    References
    ----------
    The thesis, section 10.3, Eq. 10.3-10.8; Robertson et al. (2003), Eq. 7 and Eq. 11.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> scene = 5.0 + 20.0 * np.linspace(0, 1, 64)[None, :] * np.ones((64, 1))
    >>> times = np.array([1.0, 2.3, 4.1])
    >>> frames = times[:, None, None] * scene + rng.normal(0, 3, (3, 64, 64))
    >>> curve, x = robertson_filtered(frames, times, sigma_px=2.0, offset=30.0, bit_depth=8,
    ...                               weighting="uniform", reference_level=80)
    >>> bool(abs(curve[100] / curve[80] - 70 / 50) < 0.05)  # linear: f(m) = (m - 30) / 50
    True
    """
    values = frame_stack(frames)
    _image_axes(values)
    times = exposure_times(exposure_s, values.shape[0])
    _check_distinct(times)
    bits = _bit_depth(bit_depth, values)
    iterations, tol = _iteration_options(max_iterations, tolerance)
    table = response_weights(2**bits, weighting=weighting)
    filtered = filter_frames(values, sigma_px=sigma_px, dark=dark, offset=offset)
    limits = _clip_limits(clip_limits, 2**bits)
    valid = ~clipped_after_filter(values, sigma_px=sigma_px, clip_limits=limits)
    valid = valid.reshape(values.shape[0], -1)
    flat = filtered.reshape(values.shape[0], -1)
    curve, x = _recover(flat, times, table, valid, float(offset), reference_level, iterations, tol)
    return curve, x.reshape(values.shape[1:])
