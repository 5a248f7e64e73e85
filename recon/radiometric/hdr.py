"""High dynamic range merge with a known camera response, and response histograms.

Notation of Robertson et al. (2003), which the thesis follows in section 10.3: :math:`y_{ij}` is
the value of pixel :math:`j` in the exposure :math:`i` of duration :math:`t_i`, :math:`x_j` the
(unknown) irradiance of pixel :math:`j` and :math:`f` the camera's *inverse* response, pixel value
to exposure :math:`t x` (the thesis's :math:`\\hat f^{-1}` of section 3.3, whose return value it
calls "energy"), known up to one scale factor. A curve is stored as an array ``(levels,)`` holding
:math:`f(m)` at the integral values :math:`m = 0, \\dots, levels - 1`; at fractional values (images
after a Gaussian filter, thesis Eq. 10.4) it is interpolated linearly, as the thesis prescribes
after Eq. 10.5.

Functions here take a curve as given; :mod:`recon.radiometric.response_curve` recovers one from an
exposure
series.

References
----------
- Robertson, M. A., Borman, S., & Stevenson, R. L. (2003). Estimation-theoretic approach to
  dynamic range enhancement using multiple exposures. Journal of Electronic Imaging, 12(2),
  219-228. doi:10.1117/1.1557695 (Eq. 7: the weighted irradiance estimate; the Gaussian-like
  weighting function).
- Debevec, P. E., & Malik, J. (1997). Recovering high dynamic range radiance maps from
  photographs. Proc. SIGGRAPH 97, 369-378. doi:10.1145/258734.258884 (the hat weighting).
- The thesis: Eq. 3.1-3.2 (imaging model :math:`p = f^{-1}(tI) + d`), Eq. 10.3 (irradiance
  estimate), Eq. 10.5 (the same on filtered images) and Fig. 10.3 (response histograms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recon.errors import InputError
from recon.radiometric.dark_frames import exposure_vector

__all__ = [
    "WEIGHTINGS",
    "ResponseHistogram",
    "exposure_times",
    "frame_stack",
    "interpolate_curve",
    "merge_hdr",
    "predict_values",
    "response_histogram",
    "response_weights",
]

WEIGHTINGS: tuple[str, ...] = ("gaussian", "hat", "uniform")
"""Names accepted by :func:`response_weights` (an explicit ``(levels,)`` array is accepted too)."""


# -- validation at the door ------------------------------------------------------------------


def exposure_times(exposure_s: object, count: int | None = None) -> np.ndarray:
    """Exposure times as a finite, positive float64 vector (``count`` entries when given)."""
    times = exposure_vector("exposure_s", exposure_s)
    if times.ndim != 1:
        raise InputError(
            f"exposure_s: expected a 1-D vector of exposure times, got shape {times.shape}"
        )
    if count is not None and times.size != count:
        raise InputError(
            f"exposure_s: expected one exposure time per frame ({count}), got {times.size}"
        )
    return times


def frame_stack(frames: object, name: str = "frames") -> np.ndarray:
    """A stack ``(n_exposures, ...)`` of at least two frames of finite real numbers."""
    array = np.asarray(frames)
    if array.dtype.kind not in "iuf" or array.ndim < 2:
        raise InputError(
            f"{name}: expected a real array (n_exposures, ...) with at least 2 dimensions, got "
            f"dtype {array.dtype} and shape {array.shape}"
        )
    if array.shape[0] < 2:
        raise InputError(
            f"{name}: expected an exposure series of at least 2 frames, got {array.shape[0]}"
        )
    if array.dtype.kind == "f" and not np.all(np.isfinite(array)):
        raise InputError(f"{name}: expected finite values, found NaN or infinity")
    return array


def _curve(inverse_response: object) -> np.ndarray:
    """An inverse response ``(levels,)``: finite where defined, NaN allowed outside the data."""
    curve = np.asarray(inverse_response, dtype=np.float64)
    if curve.ndim != 1 or curve.size < 2:
        raise InputError(
            f"inverse_response: expected a vector (levels,) of at least 2 values, got shape "
            f"{curve.shape}"
        )
    if np.any(np.isinf(curve)) or np.all(np.isnan(curve)):
        raise InputError("inverse_response: expected finite values (NaN only at unobserved levels)")
    return curve


def _valid_mask(valid: object, shape: tuple[int, ...]) -> np.ndarray | None:
    if valid is None:
        return None
    mask = np.asarray(valid)
    if mask.dtype != bool or mask.shape != shape:
        raise InputError(
            f"valid: expected a boolean mask of the frames' shape {shape}, got dtype "
            f"{mask.dtype} and shape {mask.shape}"
        )
    return mask


# -- weights and curve evaluation ------------------------------------------------------------


def response_weights(levels: int, *, weighting: str | np.ndarray = "gaussian") -> np.ndarray:
    """Weight :math:`w(m)` of every integral pixel value :math:`m` (Eq. 10.3's :math:`w`).

    Parameters
    ----------
    levels
        Number of pixel values, :math:`2^{bits}` (256 for 8-bit, 4096 for 12-bit data).
    weighting
        ``"gaussian"``: Robertson et al.'s (2003) Gaussian-like weighting
        :math:`g(m) = \\exp(-4 (m - c)^2 / c^2)`, :math:`c = (levels - 1) / 2`, for any bit
        depth, shifted and rescaled to reach zero continuously at both ends,
        :math:`w = (g - e^{-4}) / (1 - e^{-4})` (1 in the middle): values far from the noise
        floor and from saturation count most, and values next to saturation almost nothing
        (which matters because Eq. 10.3 multiplies the weight by :math:`t_i^2`).
        ``"hat"``: the triangle of Debevec and Malik (1997), :math:`1 - |2m / (levels-1) - 1|`.
        ``"uniform"``: all values equal. Or an explicit array ``(levels,)`` of non-negative
        weights, used as given. For the three named ones the first and last value (clipped at
        the ADC's floor or at saturation) get weight zero: a clipped value says only that the
        exposure lies beyond the range.

    Returns
    -------
    numpy.ndarray
        ``(levels,)`` float64.

    References
    ----------
    Robertson et al. (2003), J. Electronic Imaging 12(2); Debevec and Malik (1997), SIGGRAPH.

    Examples
    --------
    >>> w = response_weights(256)
    >>> float(w[0]), float(w[255]), round(float(w[128]), 3)
    (0.0, 0.0, 1.0)
    """
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 3:
        raise InputError(f"levels: expected an integer of at least 3, got {levels!r}")
    if not isinstance(weighting, str):
        table = np.asarray(weighting, dtype=np.float64)
        if table.shape != (levels,) or not np.all(np.isfinite(table)) or np.any(table < 0):
            raise InputError(
                f"weighting: expected one of {WEIGHTINGS} or {levels} finite non-negative "
                f"weights, got an array of shape {table.shape}"
            )
        return table.copy()
    centre = (levels - 1) / 2
    values = np.arange(levels, dtype=np.float64)
    if weighting == "gaussian":
        floor = np.exp(-4.0)
        table = (np.exp(-4.0 * (values - centre) ** 2 / centre**2) - floor) / (1.0 - floor)
    elif weighting == "hat":
        table = 1.0 - np.abs(values / centre - 1.0)
    elif weighting == "uniform":
        table = np.ones(levels)
    else:
        raise InputError(f"weighting: expected one of {WEIGHTINGS}, got {weighting!r}")
    table[[0, -1]] = 0.0
    return table


def interpolate_curve(curve: np.ndarray, values: np.ndarray) -> np.ndarray:
    """A curve ``(levels,)`` at (fractional) pixel values, linear between integral values.

    The thesis (section 10.3, after Eq. 10.5) stores :math:`f` at integral pixel values and
    interpolates linearly in between for the filtered, fractional values :math:`\\tilde y_{ij}`.
    Integer ``values`` index the curve directly.

    Parameters
    ----------
    curve
        ``(levels,)`` float64: an inverse response or a weighting table.
    values
        Pixel values of any shape, on the curve's index scale.

    Returns
    -------
    numpy.ndarray
        Float64 of the shape of ``values``; NaN where a value lies outside
        ``[0, levels - 1]`` (or where the curve is NaN).

    Examples
    --------
    >>> interpolate_curve(np.array([0.0, 2.0, 6.0]), np.array([0.5, 1.25, 3.0])).tolist()
    [1.0, 3.0, nan]
    """
    curve = np.asarray(curve, dtype=np.float64)
    values = np.asarray(values)
    top = curve.size - 1
    if values.dtype.kind in "iu":
        inside = (values >= 0) & (values <= top)
        return np.where(inside, curve[np.clip(values, 0, top)], np.nan)
    values = values.astype(np.float64, copy=False)
    inside = (values >= 0) & (values <= top)
    clipped = np.clip(np.where(inside, values, 0.0), 0, top)
    low = np.minimum(np.floor(clipped).astype(np.intp), top - 1)
    fraction = clipped - low
    # A value exactly at an integral level must not pick up a NaN neighbour with weight zero.
    left = np.where(fraction < 1.0, curve[low] * (1.0 - fraction), 0.0)
    right = np.where(fraction > 0.0, curve[low + 1] * fraction, 0.0)
    return np.where(inside, left + right, np.nan)


def _merge_flat(energies: np.ndarray, weights: np.ndarray, exposure_s: np.ndarray) -> np.ndarray:
    """Eq. 10.3 on ``(n_exposures, n_pixels)`` arrays of :math:`f(y_{ij})` and :math:`w(y_{ij})`.

    Samples whose energy is NaN must carry weight zero. Pixels without weight give NaN.
    """
    t = exposure_s[:, None]
    numerator = np.sum(weights * t * np.nan_to_num(energies), axis=0)
    denominator = np.sum(weights * t * t, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denominator > 0, numerator / denominator, np.nan)


# -- public operations -----------------------------------------------------------------------


def merge_hdr(
    frames: np.ndarray,
    exposure_s: np.ndarray,
    inverse_response: np.ndarray,
    *,
    weighting: str | np.ndarray = "gaussian",
    valid: np.ndarray | None = None,
) -> np.ndarray:
    """Irradiance from an exposure series and a known inverse response (Eq. 10.3).

    :math:`x_j = \\sum_i w(y_{ij}) t_i f(y_{ij}) / \\sum_i w(y_{ij}) t_i^2`: Robertson et al.'s
    (2003, Eq. 7) maximum-likelihood estimate for Gaussian noise on :math:`f(y_{ij})` of
    variance :math:`1 / w(y_{ij})`; the factor :math:`t_i^2` makes long exposures, whose
    quantization and noise are small in irradiance units, count more. With fractional values
    (filtered images, Eq. 10.5) :math:`f` and :math:`w` are interpolated linearly.

    Parameters
    ----------
    frames
        ``(n_exposures, ...)`` pixel values on the curve's index scale: integers, or fractional
        values (e.g. from :func:`recon.radiometric.response_curve.filter_frames`). Dark-subtract
        first
        (thesis Eq. 3.2) unless the curve was recovered from frames with the dark signal in.
    exposure_s
        ``(n_exposures,)`` exposure times in seconds.
    inverse_response
        ``(levels,)`` :math:`f`, e.g. from :func:`recon.radiometric.response_curve.robertson`. NaN
        entries
        (levels never observed during calibration) give their samples weight zero.
    weighting
        See :func:`response_weights`.
    valid
        Optional boolean mask of the frames' shape; ``False`` removes a sample (e.g. a pixel
        that is clipped before filtering).

    Returns
    -------
    numpy.ndarray
        ``frames.shape[1:]`` float64 irradiance in the curve's units per second; NaN for pixels
        with no usable sample (saturated or clipped in every exposure).

    References
    ----------
    Robertson et al. (2003), Eq. 7; the thesis, Eq. 10.3 and Eq. 10.5.

    Examples
    --------
    >>> curve = np.arange(256, dtype=float)  # a linear camera
    >>> frames = np.array([[10, 200], [20, 255]], dtype=np.uint8)  # 1 s and 2 s
    >>> merge_hdr(frames, [1.0, 2.0], curve).tolist()
    [10.0, 200.0]
    """
    values = frame_stack(frames)
    times = exposure_times(exposure_s, values.shape[0])
    curve = _curve(inverse_response)
    mask = _valid_mask(valid, values.shape)
    table = response_weights(curve.size, weighting=weighting)
    flat = values.reshape(values.shape[0], -1)
    energies = interpolate_curve(curve, flat)
    weights = interpolate_curve(table, flat)
    usable = np.isfinite(energies) & np.isfinite(weights)
    if mask is not None:
        usable &= mask.reshape(flat.shape)
    weights = np.where(usable, weights, 0.0)
    return _merge_flat(energies, weights, times).reshape(values.shape[1:])


def predict_values(
    irradiance: np.ndarray, exposure_s: np.ndarray, inverse_response: np.ndarray
) -> np.ndarray:
    """Pixel values a camera with this inverse response gives at each exposure.

    Inverts :math:`f` (the camera's response is :math:`f^{-1}`, thesis Eq. 3.1 without the dark
    signal): :math:`\\hat y_{ij} = f^{-1}(t_i x_j)`, linear between integral levels. The curve is
    made non-decreasing first (running maximum over its defined levels); exposures beyond its
    range give its first or last level, as a clipping camera would. Use it to check an HDR merge
    against the frames it came from.

    Parameters
    ----------
    irradiance
        Irradiance of any shape (e.g. from :func:`merge_hdr`), in the curve's units per second.
    exposure_s
        ``(n_exposures,)`` exposure times in seconds.
    inverse_response
        ``(levels,)`` :math:`f`.

    Returns
    -------
    numpy.ndarray
        ``(n_exposures, *irradiance.shape)`` float64 fractional pixel values; NaN where the
        irradiance is NaN.

    Examples
    --------
    >>> curve = np.arange(256, dtype=float)
    >>> predict_values(np.array([10.0, 200.0]), [1.0, 2.0], curve).tolist()
    [[10.0, 200.0], [20.0, 255.0]]
    """
    x = np.asarray(irradiance, dtype=np.float64)
    times = exposure_times(exposure_s)
    curve = _curve(inverse_response)
    defined = np.flatnonzero(np.isfinite(curve))
    monotone = np.maximum.accumulate(curve[defined])
    energies = times.reshape((-1,) + (1,) * x.ndim) * x
    predicted = np.interp(energies, monotone, defined.astype(np.float64))
    return np.where(np.isfinite(energies), predicted, np.nan)


@dataclass(frozen=True, eq=False)
class ResponseHistogram:
    """A two-dimensional response histogram (thesis Fig. 10.3) and its per-value statistics.

    Attributes
    ----------
    counts
        ``(n_value_bins, n_energy_bins)`` int64: samples per (pixel value, energy) bin.
    value_edges
        ``(n_value_bins + 1,)`` pixel-value bin edges (by default unit bins centred on the
        integral values).
    energy_edges
        ``(n_energy_bins + 1,)`` energy bin edges, in the curve's units.
    samples
        ``(n_value_bins,)`` samples per pixel-value bin (within the energy range or not).
    mean
        ``(n_value_bins,)`` mean energy :math:`t_i x_j` per pixel-value bin: the curve
        :math:`f` as Robertson's update (Eq. 11, thesis Eq. 10.8) sees it.
    spread
        ``(n_value_bins,)`` standard deviation of :math:`t_i x_j` per pixel-value bin; NaN
        for bins with fewer than 2 samples. Zero for an ideal, noise-free camera.
    """

    counts: np.ndarray
    value_edges: np.ndarray
    energy_edges: np.ndarray
    samples: np.ndarray
    mean: np.ndarray
    spread: np.ndarray

    @property
    def value_centres(self) -> np.ndarray:
        """``(n_value_bins,)`` centres of the pixel-value bins."""
        return 0.5 * (self.value_edges[:-1] + self.value_edges[1:])


def _edges(name: str, edges: object) -> np.ndarray:
    array = np.asarray(edges, dtype=np.float64)
    if array.ndim != 1 or array.size < 2 or not np.all(np.diff(array) > 0):
        raise InputError(
            f"{name}: expected at least 2 strictly increasing bin edges, got {edges!r}"
        )
    return array


def response_histogram(
    frames: np.ndarray,
    exposure_s: np.ndarray,
    irradiance: np.ndarray,
    *,
    value_edges: np.ndarray | None = None,
    energy_edges: np.ndarray | None = None,
    energy_bins: int = 200,
    valid: np.ndarray | None = None,
) -> ResponseHistogram:
    """Response histogram of an exposure series (thesis section 10.3, Fig. 10.3).

    Each sample :math:`(i, j)` is put in the bin of its pixel value :math:`\\tilde y_{ij}` and of
    the energy estimate of its pixel at that exposure, :math:`t_i \\tilde x_j`. An ideal, linear,
    noise-free camera fills a single line of bins; noise spreads the energies of one pixel value.
    The thesis text names the energy estimate :math:`f(\\tilde y_{ij}) / t_i`, but that is a fixed
    function of :math:`\\tilde y_{ij}` per exposure and could not show noise around a single line;
    the quantity whose per-value distribution both is a line for an ideal camera and shows noise
    is the one Eq. 10.8 averages, :math:`t_i \\tilde x_j`, which is used here.

    Parameters
    ----------
    frames
        ``(n_exposures, ...)`` pixel values :math:`\\tilde y_{ij}` (integral or fractional, on
        the curve's index scale).
    exposure_s
        ``(n_exposures,)`` exposure times in seconds.
    irradiance
        ``frames.shape[1:]`` irradiance :math:`\\tilde x_j` (e.g. from
        :func:`recon.radiometric.response_curve.robertson_filtered`); NaN pixels are left out.
    value_edges
        Pixel-value bin edges; default unit bins centred on the integers from the smallest to
        the largest value.
    energy_edges
        Energy bin edges; default ``energy_bins`` equal bins between the 0.5 and 99.5
        percentiles of the energies.
    energy_bins
        Number of energy bins when ``energy_edges`` is not given.
    valid
        Optional boolean mask of the frames' shape selecting the samples.

    Returns
    -------
    ResponseHistogram
        The 2-D counts with their edges, and mean and spread of the energy per pixel value.

    References
    ----------
    The thesis, section 10.3 and Fig. 10.3; Robertson et al. (2003), Eq. 11.

    Examples
    --------
    >>> frames = np.array([[1, 2], [2, 4]])
    >>> hist = response_histogram(frames, [1.0, 2.0], np.array([1.0, 2.0]), energy_bins=4)
    >>> hist.samples.tolist(), hist.mean.tolist()
    ([1, 2, 0, 1], [1.0, 2.0, nan, 4.0])
    """
    values = frame_stack(frames)
    times = exposure_times(exposure_s, values.shape[0])
    x = np.asarray(irradiance, dtype=np.float64)
    if x.shape != values.shape[1:]:
        raise InputError(
            f"irradiance: expected the frames' pixel shape {values.shape[1:]}, got {x.shape}"
        )
    mask = _valid_mask(valid, values.shape)
    if isinstance(energy_bins, bool) or not isinstance(energy_bins, int) or energy_bins < 1:
        raise InputError(f"energy_bins: expected a positive integer, got {energy_bins!r}")
    y = values.reshape(values.shape[0], -1).astype(np.float64)
    energy = times[:, None] * x.reshape(1, -1)
    keep = np.isfinite(energy) & np.broadcast_to(np.isfinite(x.reshape(1, -1)), energy.shape)
    if mask is not None:
        keep &= mask.reshape(y.shape)
    y, energy = y[keep], energy[keep]
    if y.size == 0:
        raise InputError("irradiance: no pixel has a finite irradiance to histogram")
    if value_edges is None:
        value_edges = np.arange(np.floor(y.min()), np.ceil(y.max()) + 1.0) - 0.5
        value_edges = np.append(value_edges, value_edges[-1] + 1.0)
    value_edges = _edges("value_edges", value_edges)
    if energy_edges is None:
        low, high = np.percentile(energy, [0.5, 99.5])
        high = high if high > low else low + 1.0
        energy_edges = np.linspace(low, high, energy_bins + 1)
    energy_edges = _edges("energy_edges", energy_edges)
    n_values, n_energies = value_edges.size - 1, energy_edges.size - 1
    value_bin = np.searchsorted(value_edges, y, side="right") - 1
    in_values = (value_bin >= 0) & (value_bin < n_values)
    value_bin, energy = value_bin[in_values], energy[in_values]
    samples = np.bincount(value_bin, minlength=n_values)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(value_bin, weights=energy, minlength=n_values) / samples
        squares = np.bincount(
            value_bin, weights=(energy - mean[value_bin]) ** 2, minlength=n_values
        )
        spread = np.where(samples >= 2, np.sqrt(squares / samples), np.nan)
    energy_bin = np.searchsorted(energy_edges, energy, side="right") - 1
    in_energies = (energy_bin >= 0) & (energy_bin < n_energies)
    flat = value_bin[in_energies] * n_energies + energy_bin[in_energies]
    counts = np.bincount(flat, minlength=n_values * n_energies).reshape(n_values, n_energies)
    return ResponseHistogram(counts, value_edges, energy_edges, samples, mean, spread)
