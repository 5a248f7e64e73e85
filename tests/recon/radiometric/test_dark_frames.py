"""Dark frames (thesis 3.3, 10.3): averaging per exposure time, interpolation, subtraction."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.radiometric.dark_frames import average_dark_frames, dark_frames_at, subtract_dark

SHAPE = (128, 128)
GAIN_DN_PER_E = 0.2  # CoolSNAP K4-like values (scenes/cameras/coolsnap_k4.yaml)
READ_NOISE_DN = 3.0  # thesis 10.3: dark noise normally distributed with a standard deviation of 3
OFFSET_DN = 100.0


def linear_dark_model(rng):
    """Per-pixel ADC offset and dark current (DN/s) with fixed-pattern noise and hot pixels."""
    offset = OFFSET_DN + 0.5 * rng.standard_normal(SHAPE)
    rate = 4.0 * np.exp(0.3 * rng.standard_normal(SHAPE))
    rate[rng.random(SHAPE) < 0.001] *= 200.0
    return offset, rate


def noisy_dark_frames(rng, offset, rate, exposure_s, count):
    """Dark frames with Poisson dark-electron noise and Gaussian read noise, quantized."""
    electrons = rng.poisson(rate * exposure_s / GAIN_DN_PER_E, size=(count,) + SHAPE)
    values = (
        offset + GAIN_DN_PER_E * electrons + READ_NOISE_DN * rng.standard_normal((count,) + SHAPE)
    )
    return np.rint(values).astype(np.uint16)


def test_averaging_n_frames_reduces_temporal_noise_by_sqrt_n(rng):
    offset, rate = linear_dark_model(rng)
    count, exposure_s = 16, 0.5
    frames = noisy_dark_frames(rng, offset, rate, exposure_s, count)
    times, means = average_dark_frames(frames, np.full(count, exposure_s))
    expected = offset + rate * exposure_s
    single_noise = np.std(frames[0] - expected)
    mean_noise = np.std(means[0] - expected)
    # The noise includes rounding to integers (variance 1/12 per frame) and Poisson noise, all
    # independent between frames, so the ratio is sqrt(N) = 4. With 16384 pixels the standard
    # deviations are known to about 1/sqrt(2 * 16384) = 0.6 %: a 3 % tolerance is 5 sigma.
    assert times.tolist() == [exposure_s]
    assert single_noise / mean_noise == pytest.approx(np.sqrt(count), rel=0.03)
    assert np.mean(means[0] - expected) == pytest.approx(0.0, abs=0.02)


def test_averages_are_grouped_by_exposure_time_in_floating_point():
    frames = np.array([[[1, 2]], [[10, 20]], [[2, 3]], [[11, 21]], [[2, 2]]], dtype=np.uint8)
    times, means = average_dark_frames(frames, [0.1, 2.0, 0.1, 2.0, 0.1])
    assert times.tolist() == [0.1, 2.0]
    np.testing.assert_allclose(means[:, 0], [[5 / 3, 7 / 3], [10.5, 20.5]])
    assert means.dtype == np.float64


def test_interpolation_between_exposure_times_is_exact_for_a_linear_dark_current(rng):
    offset, rate = linear_dark_model(rng)
    dark_times = np.array([0.1, 0.5, 2.0, 8.0])
    frames = np.stack([offset + rate * t for t in dark_times for _ in range(3)])
    times, means = average_dark_frames(frames, np.repeat(dark_times, 3))
    wanted = np.array([0.1, 0.3, 1.0, 2.0, 5.5, 8.0])
    result = dark_frames_at(wanted, times, means)
    expected = offset + rate * wanted[:, None, None]
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-9)
    assert dark_frames_at(1.0, times, means).shape == SHAPE


def test_interpolation_of_noisy_averages_keeps_the_averaged_noise(rng):
    offset, rate = linear_dark_model(rng)
    dark_times = np.array([0.25, 1.0])
    frames = np.concatenate([noisy_dark_frames(rng, offset, rate, t, 25) for t in dark_times])
    times, means = average_dark_frames(frames, np.repeat(dark_times, 25))
    midway = dark_frames_at(0.625, times, means)
    residual = midway - (offset + rate * 0.625)
    # Half of each average (noise sigma_k / 5) enters: about sqrt(3^2 + 1/12 + Poisson) / 5 /
    # sqrt(2), well under the 3 DN of a single frame.
    assert np.std(residual) < 0.6
    assert abs(np.mean(residual)) < 0.02


def test_extrapolation_is_refused_by_default_and_linear_on_request(rng):
    offset, rate = linear_dark_model(rng)
    dark_times = np.array([0.5, 1.0, 2.0])
    times, means = average_dark_frames(
        np.stack([offset + rate * t for t in dark_times]), dark_times
    )
    for outside in (0.25, 4.0):
        with pytest.raises(InputError, match="outside the dark frames' exposure range"):
            dark_frames_at(outside, times, means)
    extrapolated = dark_frames_at(np.array([0.25, 4.0]), times, means, extrapolate="linear")
    np.testing.assert_allclose(extrapolated[0], offset + rate * 0.25, atol=1e-9)
    np.testing.assert_allclose(extrapolated[1], offset + rate * 4.0, atol=1e-9)


def test_subtraction_leaves_the_signal_and_keeps_negative_values(rng):
    offset, rate = linear_dark_model(rng)
    dark_times = np.array([0.1, 1.0])
    times, means = average_dark_frames(
        np.stack([offset + rate * t for t in dark_times]), dark_times
    )
    signal = rng.uniform(-2.0, 50.0, (2,) + SHAPE)
    exposure_s = np.array([0.4, 1.0])
    frames = signal + offset + rate * exposure_s[:, None, None]
    np.testing.assert_allclose(subtract_dark(frames, exposure_s, times, means), signal, atol=1e-9)
    single = subtract_dark(frames[0], 0.4, times, means)
    np.testing.assert_allclose(single, signal[0], atol=1e-9)
    assert np.any(single < 0)


def test_a_single_dark_exposure_time_serves_only_that_time():
    times, means = np.array([1.0]), np.full((1, 2, 2), 7.0)
    np.testing.assert_allclose(dark_frames_at(1.0, times, means), 7.0)
    with pytest.raises(InputError, match="single dark exposure time"):
        dark_frames_at(2.0, times, means, extrapolate="linear")


@pytest.mark.parametrize(
    ("frames", "times", "match"),
    [
        (np.zeros((2, 2, 2)), [0.1], "one exposure time per dark frame"),
        (np.zeros((2, 2, 2)), [0.1, -0.1], "finite, positive exposure times"),
        (np.zeros((2, 2, 2)), [0.1, np.nan], "finite, positive exposure times"),
        (np.full((2, 2, 2), np.nan), [0.1, 0.1], "expected finite values"),
        (np.zeros(3), [0.1, 0.1, 0.1], r"dark_frames: expected a real array \(n_frames"),
        (np.zeros((2, 2), dtype=bool), [0.1, 0.1], "dark_frames: expected a real array"),
        (np.zeros((2, 2, 2)), [[0.1, 0.1]], "scalar or a 1-D vector"),
    ],
)
def test_average_rejects_bad_input(frames, times, match):
    with pytest.raises(InputError, match=match):
        average_dark_frames(frames, times)


def test_dark_model_and_subtraction_reject_bad_input():
    times, means = np.array([1.0, 2.0]), np.zeros((2, 3, 3))
    with pytest.raises(InputError, match="strictly increasing"):
        dark_frames_at(1.5, np.array([2.0, 1.0]), means)
    with pytest.raises(InputError, match="one frame per dark exposure time"):
        dark_frames_at(1.5, times, np.zeros((3, 3, 3)))
    with pytest.raises(InputError, match="extrapolate: expected one of"):
        dark_frames_at(1.5, times, means, extrapolate="cubic")
    with pytest.raises(InputError, match="exposure_s: expected finite, positive"):
        dark_frames_at(0.0, times, means)
    with pytest.raises(InputError, match=r"frames: expected shape \(2, 3, 3\)"):
        subtract_dark(np.zeros((2, 4, 4)), [1.0, 2.0], times, means)
    with pytest.raises(InputError, match=r"frames: expected shape \(3, 3\)"):
        subtract_dark(np.zeros((1, 3, 3)), 1.0, times, means)
    with pytest.raises(InputError, match="frames: expected finite values"):
        subtract_dark(np.full((3, 3), np.inf), 1.0, times, means)
