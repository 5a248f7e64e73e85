"""Spectral calibration (thesis Eq. 3.3-3.6) on an analytic camera with a nonlinear response."""

from __future__ import annotations

import numpy as np
import pytest

from recon.calibration.spectral import (
    HMI_FLICKER_PERIOD_S,
    drift_factors,
    plan_exposures,
    reflectance,
    run_white_factors,
    white_factors,
)
from recon.errors import InputError

BANDS = 33
RNG = np.random.default_rng(0)
SENSITIVITY = np.linspace(0.2, 1.0, BANDS) ** 2 * 400.0  # linear signal per (radiance x s)
LAMP = np.linspace(0.3, 1.5, BANDS)
WHITE = np.full(BANDS, 0.98)
DARK = 12.0


def camera(exposure_per_band, irradiance_scale=1.0):
    """p = f(c I L t) + d with f a gamma-like response and its exact inverse."""

    def photograph(radiance_over_lamp):
        linear = SENSITIVITY[:, None] * irradiance_scale * LAMP[:, None] * radiance_over_lamp
        linear = linear * exposure_per_band[:, None]
        return np.sqrt(linear) * 30.0 + DARK

    return photograph


def inverse(values):
    return (values / 30.0) ** 2


def test_white_factors_and_eq_3_5_recover_the_brdf_exactly():
    white_exposure = np.full(BANDS, 0.5)
    white_pixels = camera(white_exposure)(np.tile(WHITE[:, None] / np.pi, (1, 50)))
    factors = white_factors(
        white_pixels, white_exposure, LAMP, WHITE, white_dark=DARK, inverse_response=inverse
    )
    assert np.allclose(factors, 1.0 / SENSITIVITY, rtol=1e-12)  # F = 1 / camera sensitivity
    brdf = RNG.uniform(0.01, 0.3, size=(BANDS, 20))
    exposure = plan_exposures(0.2, factors, LAMP)
    values = camera(exposure)(brdf)
    run = run_white_factors(
        white_pixels, white_exposure, WHITE, white_dark=DARK, inverse_response=inverse
    )
    assert np.allclose(run, factors / LAMP)
    recovered = reflectance(values, exposure, run, dark=DARK, inverse_response=inverse)
    assert np.allclose(recovered, brdf, rtol=1e-12)


def test_exposure_plan_equalizes_a_grey_sample_and_respects_the_hmi_period():
    factors = 1.0 / SENSITIVITY
    exposure = plan_exposures(0.2, factors, LAMP)
    grey = camera(exposure)(np.full((BANDS, 1), 0.2 / np.pi))
    assert np.ptp(grey) < 1e-9  # same signal level in every band (thesis 3.3)
    hmi = plan_exposures(0.2, factors, LAMP, round_to_s=HMI_FLICKER_PERIOD_S)
    periods = hmi / HMI_FLICKER_PERIOD_S
    assert np.allclose(periods, np.round(periods), atol=1e-9) and np.all(periods >= 1)
    assert np.all(hmi >= exposure - 1e-12) and np.all(hmi - exposure < HMI_FLICKER_PERIOD_S)


def test_lamp_drift_is_undone_by_the_monitor_factors():
    brightness = np.array([1.0, 1.04, 0.97, 1.1])
    monitor = brightness[:, None] * np.linspace(0.5, 2.0, 40)[None, :]
    drift = drift_factors(monitor)
    assert np.allclose(drift, 1.0 / brightness)
    factors = 1.0 / SENSITIVITY
    exposure = plan_exposures(0.2, factors, LAMP)
    brdf = np.full((BANDS, 3), 0.1)
    for point, scale in enumerate(brightness):
        values = camera(exposure, irradiance_scale=scale)(brdf)
        recovered = reflectance(
            values,
            exposure,
            factors / LAMP,
            dark=DARK,
            drift=drift[point],
            inverse_response=inverse,
        )
        assert np.allclose(recovered, brdf, rtol=1e-12)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: white_factors(np.ones((3, 4)), np.ones(2), np.ones(3), np.ones(3)), "exposure_s"),
        (lambda: white_factors(np.zeros((3, 4)), np.ones(3), np.ones(3), np.ones(3)), "no signal"),
        (lambda: plan_exposures(-1.0, np.ones(3), np.ones(3)), "base_s"),
        (lambda: plan_exposures(1.0, np.ones(3), np.ones(3), limits_s=(0, 0.5)), "outside"),
        (lambda: drift_factors(np.zeros((2, 5))), "all-zero"),
        (lambda: reflectance(np.full((3, 2), np.nan), np.ones(3), np.ones(3)), "finite"),
        (lambda: reflectance(np.ones((3, 2)), np.ones(3), np.ones(3), drift=0.0), "drift"),
    ],
)
def test_bad_calibration_input_is_refused(call, message):
    with pytest.raises(InputError, match=message):
        call()
