"""One 45/0 reading spectralizes an RGB BTF (recon.btf.reading_spectralization): a BTF of one
colour whose brightness varies by texel and pair is recovered exactly at every texel; on a
texture of several colours the mean over the measuring spot at the reading's pair is the
reading (the area constraint of Eq. 6.9); the pair nearest 45/0 is chosen, and one beyond the
tolerance refused."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from recon.btf.reading_spectralization import (
    TOLERANCE_DEG,
    MeasuringSpot,
    Reading45,
    read_reading_csv,
    reading_pair,
    spectralize_from_reading,
)
from recon.errors import InputError
from recon.measured_data import read_camera_sensitivities, read_spectra_csv
from recon.spectra import DEFAULT_GRID, SampledSpectra, from_colour, resample

CAMERA = "Nikon D850"
PAIRS, SIDE = 3, 12


def _unit(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    theta, phi = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _camera_values(truth: np.ndarray) -> np.ndarray:
    """The camera's values under D65 (a light the spectralization does not know)."""
    response = resample(read_camera_sensitivities(CAMERA), DEFAULT_GRID).values.T
    d65 = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID).values
    return truth @ (response * (d65 * DEFAULT_GRID.quadrature_weights())[:, None])


def _patches(*names: str) -> np.ndarray:
    chart = resample(
        read_spectra_csv("spectra/reflectances/macbeth_colorchecker.csv"), DEFAULT_GRID
    )
    return np.stack([chart.row(name).values for name in names])


def _reading(spectrum: np.ndarray) -> Reading45:
    return Reading45(SampledSpectra(DEFAULT_GRID, spectrum[None]), "test")


def test_one_colour_is_recovered_exactly_at_every_texel():
    rng = np.random.default_rng(0)
    shading = rng.uniform(0.3, 1.2, (PAIRS, SIDE, SIDE, 1))  # texel and pair brightness
    truth = shading * _patches("patch07")[0]  # orange
    spot = MeasuringSpot(2, 3, 5, 4)
    inside = truth[1, 3:7, 2:7].reshape(-1, DEFAULT_GRID.size).mean(axis=0)
    result = spectralize_from_reading(
        _camera_values(truth),
        _reading(inside),
        read_camera_sensitivities(CAMERA),
        pair=1,
        spot=spot,
        tol=1e-10,
    )
    assert result.grid == DEFAULT_GRID
    assert np.max(np.abs(result.cube - truth)) < 1e-4 * truth.max()
    assert result.fit_residual_pct.max() < 1e-9


def test_the_mean_over_the_measuring_spot_is_the_reading():
    colours = _patches("patch02", "patch14", "patch16")  # light skin, green, yellow
    labels = np.random.default_rng(1).integers(0, 3, (SIDE, SIDE))
    truth = colours[labels][None] * np.array([0.6, 1.0, 0.8])[:, None, None, None]
    reading = truth[2].reshape(-1, DEFAULT_GRID.size).mean(axis=0)
    result = spectralize_from_reading(
        _camera_values(truth), _reading(reading), read_camera_sensitivities(CAMERA), pair=2
    )
    mean = result.cube[2].reshape(-1, DEFAULT_GRID.size).mean(axis=0)
    assert np.max(np.abs(mean - reading)) < 1e-3 * reading.max()


@pytest.mark.parametrize(
    ("angles", "pair", "distance"),
    [
        ([(0, 0), (45, 0), (45, 30)], 1, 0.0),  # 45/0 itself
        ([(30, 0), (60, 0), (45, 60)], 0, 15.0),  # 30/0 and 60/0 alike: the first
        ([(0, 0), (50, 5)], 1, np.hypot(5, 5)),
    ],
)
def test_the_pair_nearest_45_0_is_chosen(angles, pair, distance):
    light = np.array([_unit(theta, 120) for theta, _ in angles])
    view = np.array([_unit(theta, 250) for _, theta in angles])
    chosen, offset = reading_pair(light, view)
    assert chosen == pair and offset == pytest.approx(distance, abs=1e-6)


def test_no_pair_near_45_0_is_refused():
    light = np.array([_unit(0), _unit(45)])
    view = np.array([_unit(0), _unit(TOLERANCE_DEG + 1)])
    with pytest.raises(InputError, match="no direction pair near 45/0"):
        reading_pair(light, view)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("wavelength_nm,reflectance\n400,0.2\n500,1.6\n", "expected reflectance factors in"),
        ("wavelength_nm,reflectance\n400,-0.1\n500,0.5\n", "expected reflectance factors in"),
        ("wavelength_nm,reflectance\n400,nan\n500,0.5\n", "expected 2 finite numbers"),
        ("wavelength_nm,R\n400,0.2\n500,0.5\n", "expected wavelength_nm,reflectance"),
        ("wavelength_nm,reflectance\n500,0.2\n400,0.5\n", "strictly increasing"),
    ],
)
def test_bad_readings_are_refused(tmp_path, text, message):
    path = tmp_path / "reading.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_reading_csv(path)


@pytest.mark.parametrize("spot", [MeasuringSpot(10, 0, 3, 3), MeasuringSpot(0, 0, 0, 4)])
def test_a_measuring_spot_outside_the_texture_is_refused(spot):
    with pytest.raises(InputError, match="inside the 12 x 12 texels"):
        spot.texels((SIDE, SIDE))
