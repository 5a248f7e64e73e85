"""Dark frames: averaging per exposure time, interpolation between exposure times, subtraction.

The thesis models a pixel value as :math:`p_x = f^{-1}(t I_x) + d_x` (section 3.3, Eq. 3.1):
the dark counts :math:`d_x` (ADC offset, dark current, fixed-pattern noise, hot pixels) add to the
camera's response and are subtracted before inverting it (Eq. 3.2,
:math:`I_x = f^{-1}(p_x - d_x) / t`; Eq. 3.5 with :math:`d_{x, t_\\lambda}`). Because the cooled
CoolSNAP K4's dark signal depends on the exposure time only, the thesis captures many dark frames
per exposure time beforehand (50 in section 3.3, 200 in section 10.3), averages them in floating
point, and "interpolate[s] between the respective averaged dark frames linearly" for the exposure
time of each measurement (section 3.3). Averaging :math:`N` frames divides the temporal noise's
standard deviation by :math:`\\sqrt N`; a single dark frame subtracted from a single data frame
would instead add its full noise (the thesis's remark on :math:`\\sqrt{2}`).

Interpolation is exact for a dark signal that is linear in the exposure time (offset plus dark
current times :math:`t`), which is what dark current is at a constant sensor temperature.

Extrapolation policy: by default an exposure time outside the range of the averaged dark frames
is refused (:class:`~recon.errors.InputError`), since the thesis preselects the dark
exposure times to cover the capture; ``extrapolate="linear"`` continues the first or last
segment linearly instead (right for a linear dark signal, and it amplifies the remaining noise
of the two nearest averages by the extrapolation factor).

References
----------
- The thesis: section 3.3 (Eq. 3.1, 3.2, 3.5; dark frames averaged per exposure time and
  interpolated linearly) and section 10.3 (200 dark frames per exposure time, averaged with
  floating-point accuracy; Fig. 10.2d).
- Janesick, J. R. (2007). Photon Transfer. SPIE Press. doi:10.1117/3.725073 (dark current, fixed
  pattern noise).
"""

from __future__ import annotations

import numpy as np

from recon.errors import InputError

__all__ = [
    "EXTRAPOLATION",
    "average_dark_frames",
    "dark_frames_at",
    "exposure_vector",
    "subtract_dark",
]

EXTRAPOLATION: tuple[str, ...] = ("none", "linear")
"""Policies for exposure times outside the dark frames' range: refuse, or continue linearly."""


def exposure_vector(name: str, exposure_s: object) -> np.ndarray:
    """Exposure times in seconds (a scalar or a 1-D vector), finite and positive."""
    try:
        times = np.asarray(exposure_s, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(
            f"{name}: expected exposure times in seconds, got {exposure_s!r}"
        ) from error
    if times.ndim > 1 or times.size == 0:
        raise InputError(
            f"{name}: expected a scalar or a 1-D vector of exposure times, got shape {times.shape}"
        )
    if not np.all(np.isfinite(times)) or np.any(times <= 0):
        raise InputError(
            f"{name}: expected finite, positive exposure times in seconds, got {times}"
        )
    return times


def _stack(name: str, frames: object) -> np.ndarray:
    array = np.asarray(frames)
    if array.dtype.kind not in "iuf" or array.ndim < 2:
        raise InputError(
            f"{name}: expected a real array (n_frames, ...) of frames, got dtype {array.dtype} "
            f"and shape {array.shape}"
        )
    if array.dtype.kind == "f" and not np.all(np.isfinite(array)):
        raise InputError(f"{name}: expected finite values, found NaN or infinity")
    return array


def average_dark_frames(
    dark_frames: np.ndarray, exposure_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Average dark frames per exposure time (thesis sections 3.3 and 10.3).

    Parameters
    ----------
    dark_frames
        ``(n_frames, ...)`` raw dark frames (shutter closed), any mix of exposure times.
    exposure_s
        ``(n_frames,)`` exposure time of every frame in seconds; frames whose times are equal
        (exactly, as read from the same capture settings) are averaged together.

    Returns
    -------
    dark_exposure_s : numpy.ndarray
        ``(n_times,)`` the distinct exposure times, increasing.
    mean_dark_frames : numpy.ndarray
        ``(n_times, ...)`` float64 mean frame per exposure time, in floating point (no rounding).

    Examples
    --------
    >>> frames = np.array([[[10]], [[12]], [[20]], [[22]]], dtype=np.uint16)
    >>> times, means = average_dark_frames(frames, [0.5, 0.5, 1.0, 1.0])
    >>> times.tolist(), means.ravel().tolist()
    ([0.5, 1.0], [11.0, 21.0])
    """
    frames = _stack("dark_frames", dark_frames)
    times = exposure_vector("exposure_s", exposure_s)
    if times.ndim != 1 or times.size != frames.shape[0]:
        raise InputError(
            f"exposure_s: expected one exposure time per dark frame ({frames.shape[0]}), got "
            f"shape {times.shape}"
        )
    distinct, group = np.unique(times, return_inverse=True)
    means = np.stack(
        [frames[group == index].mean(axis=0, dtype=np.float64) for index in range(distinct.size)]
    )
    return distinct, means


def _dark_model(dark_exposure_s: object, mean_dark_frames: object) -> tuple[np.ndarray, np.ndarray]:
    times = exposure_vector("dark_exposure_s", dark_exposure_s)
    times = np.atleast_1d(times)
    means = _stack("mean_dark_frames", mean_dark_frames).astype(np.float64, copy=False)
    if means.shape[0] != times.size:
        raise InputError(
            f"mean_dark_frames: expected one frame per dark exposure time ({times.size}), got "
            f"{means.shape[0]}"
        )
    if np.any(np.diff(times) <= 0):
        raise InputError(
            f"dark_exposure_s: expected strictly increasing exposure times (as returned by "
            f"average_dark_frames), got {times}"
        )
    return times, means


def dark_frames_at(
    exposure_s: float | np.ndarray,
    dark_exposure_s: np.ndarray,
    mean_dark_frames: np.ndarray,
    *,
    extrapolate: str = "none",
) -> np.ndarray:
    """Dark frame :math:`d_{x,t}` at any exposure time by linear interpolation (thesis 3.3).

    Between the two neighbouring dark exposure times :math:`t_k \\le t \\le t_{k+1}`:
    :math:`d(t) = d_k + (t - t_k) (d_{k+1} - d_k) / (t_{k+1} - t_k)`; at a dark exposure time
    exactly, its averaged frame.

    Parameters
    ----------
    exposure_s
        An exposure time in seconds, or a vector ``(n,)`` of them.
    dark_exposure_s, mean_dark_frames
        The dark model from :func:`average_dark_frames`: increasing times ``(n_times,)`` and
        their mean frames ``(n_times, ...)``.
    extrapolate
        ``"none"`` (default): an exposure time outside ``[dark_exposure_s[0],
        dark_exposure_s[-1]]`` raises :class:`~recon.errors.InputError`. ``"linear"``:
        the first or last segment is continued linearly (needs two dark exposure times).

    Returns
    -------
    numpy.ndarray
        float64 ``(...)`` for a scalar exposure time, ``(n, ...)`` for a vector.

    Examples
    --------
    >>> times, means = np.array([1.0, 3.0]), np.array([[[10.0]], [[30.0]]])
    >>> float(dark_frames_at(2.0, times, means)[0, 0])
    20.0
    >>> float(dark_frames_at(4.0, times, means, extrapolate="linear")[0, 0])
    40.0
    """
    times, means = _dark_model(dark_exposure_s, mean_dark_frames)
    wanted = exposure_vector("exposure_s", exposure_s)
    if extrapolate not in EXTRAPOLATION:
        raise InputError(f"extrapolate: expected one of {EXTRAPOLATION}, got {extrapolate!r}")
    flat = np.atleast_1d(wanted)
    outside = (flat < times[0]) | (flat > times[-1])
    if np.any(outside) and extrapolate == "none":
        raise InputError(
            f"exposure_s: {flat[outside]} s lies outside the dark frames' exposure range "
            f"[{times[0]}, {times[-1]}] s; capture dark frames there or pass "
            "extrapolate='linear'"
        )
    if times.size == 1:
        if np.any(flat != times[0]):
            raise InputError(
                f"dark_exposure_s: a single dark exposure time ({times[0]} s) can neither be "
                f"interpolated nor extrapolated to {flat} s"
            )
        result = np.repeat(means, flat.size, axis=0)
    else:
        segment = np.clip(np.searchsorted(times, flat, side="right") - 1, 0, times.size - 2)
        start, end = times[segment], times[segment + 1]
        fraction = ((flat - start) / (end - start)).reshape((-1,) + (1,) * (means.ndim - 1))
        result = means[segment] + fraction * (means[segment + 1] - means[segment])
    return result[0] if wanted.ndim == 0 else result


def subtract_dark(
    frames: np.ndarray,
    exposure_s: float | np.ndarray,
    dark_exposure_s: np.ndarray,
    mean_dark_frames: np.ndarray,
    *,
    extrapolate: str = "none",
) -> np.ndarray:
    """Frames minus the dark frame of their exposure time: :math:`p_x - d_{x,t}` (Eq. 3.2, 3.5).

    Negative results are kept: clipping them at zero would bias dark, noisy pixels (thesis
    Fig. 10.3).

    Parameters
    ----------
    frames
        One frame ``(...)`` with a scalar ``exposure_s``, or a stack ``(n, ...)`` with a vector
        ``exposure_s`` ``(n,)``. The pixel shape must be that of the dark frames.
    exposure_s
        Exposure time(s) in seconds.
    dark_exposure_s, mean_dark_frames
        The dark model from :func:`average_dark_frames`.
    extrapolate
        See :func:`dark_frames_at`.

    Returns
    -------
    numpy.ndarray
        float64 of the frames' shape.

    Examples
    --------
    >>> times, means = np.array([1.0, 3.0]), np.array([[[10.0]], [[30.0]]])
    >>> subtract_dark(np.array([[[25]], [[15]]]), [2.0, 1.0], times, means).ravel().tolist()
    [5.0, 5.0]
    """
    _, means = _dark_model(dark_exposure_s, mean_dark_frames)
    values = np.asarray(frames)
    if values.dtype.kind not in "iuf":
        raise InputError(f"frames: expected real pixel values, got dtype {values.dtype}")
    if values.dtype.kind == "f" and not np.all(np.isfinite(values)):
        raise InputError("frames: expected finite values, found NaN or infinity")
    wanted = exposure_vector("exposure_s", exposure_s)
    pixel_shape = means.shape[1:]
    expected = pixel_shape if wanted.ndim == 0 else (wanted.size,) + pixel_shape
    if values.shape != expected:
        raise InputError(
            f"frames: expected shape {expected} (one frame per exposure time, the dark frames' "
            f"pixel shape {pixel_shape}), got {values.shape}"
        )
    dark = dark_frames_at(wanted, dark_exposure_s, means, extrapolate=extrapolate)
    return values.astype(np.float64) - dark
