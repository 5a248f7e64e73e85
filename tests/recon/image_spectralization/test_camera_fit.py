"""The camera term fitted to spots (``recon.image_spectralization.camera_fit``): a measured
camera under CIE D65, with the response given bare, is found from the ColorChecker's 24
reflectances to what the camera sees through D65 (Eq. 9.4), where a gain per channel is not;
noisy spots keep a lower degree."""

from __future__ import annotations

import colour
import numpy as np

from recon.image_spectralization.camera_fit import camera_term
from recon.measured_data import read_camera_sensitivities
from recon.spectra import DEFAULT_GRID, from_colour, resample

CAMERA = "Nikon D850"


def _checker() -> np.ndarray:
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    return np.array([resample(from_colour(sd), DEFAULT_GRID).values for sd in chart.values()])


def _truth(response) -> np.ndarray:
    """``(K, 3)``: the bare response's band integrals through D65, in the images' unit."""
    d65 = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID).values
    camera = resample(response, DEFAULT_GRID).values.T
    return camera * (d65 * DEFAULT_GRID.quadrature_weights())[:, None]


def test_d65_is_found_where_gains_alone_miss_it():
    response = read_camera_sensitivities(CAMERA)
    truth = _truth(response)
    checker = _checker()
    spots, held_out = checker[::2], checker[1::2]
    fitted = camera_term(response, DEFAULT_GRID, spots @ truth, spots)
    gains = camera_term(response, DEFAULT_GRID, spots @ truth, spots, max_degree=0)
    assert gains.degrees == (0, 0, 0)

    def error(term) -> float:  # relative error of the held-out fields' camera values, %
        return float(
            100 * np.abs(held_out @ (term.matrix - truth)).max() / (held_out @ truth).max()
        )

    # Measured: 0.05 % with the fitted factor, 1.7 % with gains alone.
    assert error(fitted) < 0.2 < 1.0 < error(gains), (error(fitted), error(gains))
    assert np.all(fitted.fit_residual_pct < 0.2) and np.all(gains.fit_residual_pct > 0.2)


def test_noisy_spots_lower_the_degree():
    response = read_camera_sensitivities(CAMERA)
    truth = _truth(response)
    spots = _checker()[::2]
    exact = camera_term(response, DEFAULT_GRID, spots @ truth, spots)
    noisy = [
        camera_term(response, DEFAULT_GRID, values, spots)
        for values in (
            spots @ truth * (1 + 0.03 * np.random.default_rng(seed).standard_normal((12, 3)))
            for seed in range(5)
        )
    ]
    # Measured: degrees (4, 3, 4) from exact spots; 1.0 per channel on average at 3 % noise.
    assert sum(exact.degrees) == 11
    assert np.mean([term.degrees for term in noisy]) < 2
