"""Component spectra of the rigs (twin.components) against physics, colour and the thesis."""

import colour
import numpy as np
import pytest
from scipy import integrate, special

from recon.errors import InputError
from recon.spectra import (
    DEFAULT_GRID,
    SampledSpectra,
    WavelengthGrid,
    band_integrals,
    resample,
    to_colour,
)
from twin.components.detectors import CCDQuantumEfficiency, rgb_camera_response
from twin.components.lamps import (
    FINE_GRID,
    HMILamp,
    PhosphorWhiteLED,
    QTHLamp,
    cie_illuminant,
    irradiance_at,
    planck_spectral_radiance,
)
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import (
    camera_chart_reflectances,
    colorchecker_reflectances,
    zenith_white_reflectance,
)

VISIBLE = WavelengthGrid.regular(360, 780, 1)


def _cct(spectrum: SampledSpectra) -> float:
    xyz = colour.sd_to_XYZ(to_colour(spectrum))
    return float(colour.temperature.XYZ_to_CCT_Ohno2013(xyz)[0])


@pytest.mark.parametrize("temperature_k", [2000.0, 3000.0, 6000.0, 10000.0])
def test_black_body_equals_colour_planck_law_within_a_tenth_of_a_percent(temperature_k):
    wavelengths = VISIBLE.wavelengths_nm
    ours = planck_spectral_radiance(wavelengths, temperature_k)
    # colour: wavelength in m, result in W m^-2 sr^-1 m^-1
    theirs = colour.colorimetry.planck_law(wavelengths * 1e-9, temperature_k) * 1e-9
    np.testing.assert_allclose(ours, theirs, rtol=1e-3)


def test_qth_lamp_has_a_black_body_shape_and_the_requested_power():
    lamp = QTHLamp(temperature_k=3000.0, radiant_intensity_w_sr=20.0)
    intensity = lamp.intensity(FINE_GRID).values
    planck = colour.colorimetry.planck_law(FINE_GRID.wavelengths_nm * 1e-9, 3000.0)
    np.testing.assert_allclose(intensity / intensity[800], planck / planck[800], rtol=1e-3)
    inside = (FINE_GRID.wavelengths_nm >= 380) & (FINE_GRID.wavelengths_nm <= 780)
    assert np.trapezoid(intensity[inside], FINE_GRID.wavelengths_nm[inside]) == pytest.approx(20.0)
    assert _cct(lamp.intensity(VISIBLE)) == pytest.approx(3000.0, rel=0.01)


def test_qth_lamp_does_not_flicker():
    lamp = QTHLamp()
    power = lamp.intensity(DEFAULT_GRID).values
    # Steady output: the integral over any window is the constant power times its length,
    # whatever the window's start.
    for t0, exposure in [(0.0, 0.05), (0.0123, 0.05), (3.7, 0.001), (0.5, 2.0)]:
        np.testing.assert_allclose(
            lamp.exposure_integral(DEFAULT_GRID, t0, exposure).values,
            power * exposure,
            rtol=1e-12,
        )


def test_hmi_spectrum_has_the_545_9_nm_peak_and_a_daylight_colour_temperature():
    lamp = HMILamp()
    intensity = lamp.intensity(FINE_GRID).values
    green = (FINE_GRID.wavelengths_nm > 530) & (FINE_GRID.wavelengths_nm < 560)
    assert FINE_GRID.wavelengths_nm[green][np.argmax(intensity[green])] == pytest.approx(
        545.9, abs=0.25
    )
    continuum, _ = lamp.continuum_and_lines(np.array([545.9]))
    assert intensity[green].max() > 2 * continuum[0]
    assert 5500 < _cct(lamp.intensity(VISIBLE)) < 6500


def test_hmi_energy_over_any_1_15_s_window_is_constant(rng):
    lamp = HMILamp()
    period = 1 / lamp.flicker_hz
    energies = np.array(
        [lamp.exposure_integral(FINE_GRID, t0, period).values for t0 in rng.uniform(0, period, 25)]
    )
    spread = energies.max(axis=0) / energies.min(axis=0) - 1
    assert spread.max() < 1e-6
    # Without the slow drift, windows anywhere in the first hour are identical too.
    steady = HMILamp(drift_fraction=0.0)
    energies = np.array(
        [
            steady.exposure_integral(FINE_GRID, t0, 2 * period).values
            for t0 in rng.uniform(0, 3600, 10)
        ]
    )
    assert (energies.max(axis=0) / energies.min(axis=0) - 1).max() < 1e-9


def test_hmi_energy_over_a_50_ms_window_varies_with_phase_in_the_lines_only(rng):
    lamp = HMILamp(drift_fraction=0.0)
    probe = WavelengthGrid(np.array([545.9, 650.0]))
    energies = np.array(
        [lamp.exposure_integral(probe, t0, 0.05).values for t0 in rng.uniform(0, 1, 200)]
    )
    spread = energies.max(axis=0) / energies.min(axis=0) - 1
    # Predicted peak-to-peak of the line energy: 2 m sin(pi f T) / (pi f) relative to T.
    continuum, lines = lamp.continuum_and_lines(probe.wavelengths_nm)
    f, m, exposure = lamp.flicker_hz, lamp.flicker_depth, 0.05
    line_swing = 2 * m * abs(np.sin(np.pi * f * exposure)) / (np.pi * f)
    predicted = (
        lines[0] * line_swing / (exposure * (continuum[0] + lines[0]) - lines[0] * line_swing / 2)
    )
    assert spread[0] == pytest.approx(predicted, rel=0.02)
    assert spread[0] > 0.05
    assert spread[1] < 1e-9


def test_hmi_exposure_integral_matches_numerical_time_integration():
    lamp = HMILamp(drift_fraction=0.0, flicker_phase_rad=0.7)
    probe = WavelengthGrid(np.array([435.8, 545.9, 578.0, 620.0]))
    exact = lamp.exposure_integral(probe, 0.0313, 0.0417).values
    numeric = np.array(
        [
            integrate.quad(
                lambda t, k=k: lamp.intensity(probe, t).values[k], 0.0313, 0.073, epsabs=0
            )[0]
            for k in range(probe.size)
        ]
    )
    np.testing.assert_allclose(exact, numeric, rtol=1e-9)


def test_hmi_drift_changes_output_over_hours():
    lamp = HMILamp()
    start = lamp.exposure_integral(DEFAULT_GRID, 0.0, 1 / 15).values
    hours_later = lamp.exposure_integral(DEFAULT_GRID, 5 * 3600.0, 1 / 15).values
    expected = lamp.drift(5 * 3600.0 + 1 / 30) / lamp.drift(1 / 30)
    np.testing.assert_allclose(hours_later / start, expected, rtol=1e-12)
    assert abs(expected - 1) > 0.01


@pytest.mark.parametrize("model", ["VS-07", "VS-10", "VS-20"])
def test_lctf_band_integral_of_a_flat_spectrum_matches_the_analytic_value(model):
    lctf = LiquidCrystalTunableFilter.varispec(model)
    grid = WavelengthGrid.regular(300, 900, 0.5)
    flat = SampledSpectra(grid, np.ones(grid.size))
    numeric = band_integrals(flat, lctf.transmission(grid))
    sigma = lctf.fwhm_nm / (2 * np.sqrt(2 * np.log(2)))
    centres = np.asarray(lctf.band_centres_nm)
    gaussian_area = (
        sigma
        * np.sqrt(2 * np.pi)
        * 0.5
        * (
            special.erf((900 - centres) / (sigma * np.sqrt(2)))
            - special.erf((300 - centres) / (sigma * np.sqrt(2)))
        )
    )
    analytic = (
        lctf.peak_transmission() * gaussian_area + lctf.polarizer_transmission * lctf.leakage * 600
    )
    np.testing.assert_allclose(numeric, analytic, rtol=0.01)


def test_lctf_transmission_falls_toward_short_wavelengths():
    lctf = LiquidCrystalTunableFilter()
    peaks = lctf.peak_transmission()
    assert len(peaks) == 33 and np.all(np.diff(peaks) > 0)
    assert peaks[0] < peaks[-1] / 3
    assert peaks[-1] <= lctf.polarizer_transmission
    transmission = lctf.transmission(FINE_GRID)
    assert transmission.names[0] == "lctf_400nm"
    far = np.abs(FINE_GRID.wavelengths_nm - 550) > 60
    np.testing.assert_allclose(
        transmission.row("lctf_550nm").values[far],
        lctf.polarizer_transmission * lctf.leakage,
        rtol=1e-6,
    )


def test_white_led_is_a_blue_pumped_phosphor_spectrum():
    led = PhosphorWhiteLED()
    intensity = led.intensity(VISIBLE).values
    assert VISIBLE.wavelengths_nm[np.argmax(intensity)] == pytest.approx(450, abs=2)
    assert 5000 < _cct(led.intensity(VISIBLE)) < 7000


def test_cie_illuminants_come_from_colour():
    d65 = cie_illuminant("D65", DEFAULT_GRID)
    assert d65.values[np.searchsorted(DEFAULT_GRID.wavelengths_nm, 560)] == pytest.approx(
        100, rel=0.01
    )
    with pytest.raises(InputError, match="SDS_ILLUMINANTS"):
        cie_illuminant("D99", DEFAULT_GRID)


def test_ccd_quantum_efficiency_is_blue_poor_and_peaks_near_490_nm():
    qe = CCDQuantumEfficiency()(DEFAULT_GRID).values
    assert DEFAULT_GRID.wavelengths_nm[np.argmax(qe)] == pytest.approx(490, abs=10)
    assert 0.5 < qe.max() <= 0.55 and qe[0] < 0.8 * qe.max()


@pytest.mark.parametrize(
    "camera", ["Nikon 5100 (NPL)", "Nikon D70", "Nikon D100", "Aptina MT9M131"]
)
def test_rgb_camera_responses_peak_in_order_blue_green_red(camera):
    response = rgb_camera_response(camera, DEFAULT_GRID)
    assert response.names == ("R", "G", "B") and response.values.max() == pytest.approx(
        1.0, abs=0.02
    )
    peaks = DEFAULT_GRID.wavelengths_nm[np.argmax(response.values, axis=1)]
    assert peaks[2] < peaks[1] < peaks[0]


def test_zenith_white_is_nearly_perfect_and_slightly_lower_in_the_blue():
    white = zenith_white_reflectance(DEFAULT_GRID).values
    assert np.all((white > 0.96) & (white <= 1.0)) and white[0] < white[-1]


def test_colorchecker_sources_agree():
    ohta = colorchecker_reflectances(DEFAULT_GRID)
    isetbio = colorchecker_reflectances(DEFAULT_GRID, source="isetbio")
    assert ohta.values.shape == isetbio.values.shape == (24, 33)
    assert ohta.names == isetbio.names and ohta.names[0] == "dark skin"
    # Two measurements of the same chart: every patch within a few percent reflectance.
    assert np.all(np.median(np.abs(ohta.values - isetbio.values), axis=1) < 0.08)
    assert np.median(np.abs(ohta.values - isetbio.values)) < 0.02


def test_the_camera_chart_holds_the_same_240_measured_fields_on_any_grid():
    fine = camera_chart_reflectances(WavelengthGrid.regular(380, 780, 5))
    coarse = camera_chart_reflectances(WavelengthGrid.regular(380, 780, 10))
    assert fine.values.shape == (240, 81) and coarse.values.shape == (240, 41)
    assert fine.names == coarse.names and len(set(fine.names)) == 240
    kinds = [name.split()[0] for name in fine.names]
    assert (kinds.count("colorchecker"), kinds.count("esser")) == (24, 31)
    assert np.all((fine.values >= 0) & (fine.values <= 1))
    # The 10 nm fields are the cell means of the 5 nm ones.
    means = resample(fine, coarse.grid, method="box", out_of_range="clamp").values
    np.testing.assert_allclose(np.clip(means, 0, 1), coarse.values, atol=1e-12)
    # Every field is measured, not a copy of another: no two within 0.5 % reflectance (RMS).
    distances = np.sqrt(((fine.values[:, None] - fine.values[None]) ** 2).mean(axis=2))
    assert np.min(distances + np.eye(240)) > 0.005


def test_irradiance_follows_the_inverse_square_law():
    intensity = QTHLamp().intensity(DEFAULT_GRID)
    np.testing.assert_allclose(irradiance_at(intensity, 2.0).values, intensity.values / 4)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: planck_spectral_radiance(np.array([500.0]), -3.0), "temperature"),
        (lambda: QTHLamp().exposure_integral(DEFAULT_GRID, 0.0, -1.0), "exposure_s"),
        (lambda: HMILamp().exposure_integral(DEFAULT_GRID, np.nan, 0.1), "t0_s"),
        (lambda: HMILamp(flicker_depth=1.5), "flicker_depth"),
        (lambda: QTHLamp(radiant_intensity_w_sr=0.0).intensity(DEFAULT_GRID), "radiant_intensity"),
        (lambda: LiquidCrystalTunableFilter.varispec("VS-15"), "VS-07"),
        (lambda: LiquidCrystalTunableFilter(fwhm_nm=-1.0), "fwhm_nm"),
        (lambda: LiquidCrystalTunableFilter(band_centres_nm=(500.0, 490.0)), "band_centres_nm"),
        (lambda: rgb_camera_response("Kodak 14n", DEFAULT_GRID), "camera"),
        (lambda: colorchecker_reflectances(DEFAULT_GRID, source="nope"), "source"),
        (lambda: camera_chart_reflectances(VISIBLE), "380-780 nm"),
        (lambda: irradiance_at(QTHLamp().intensity(DEFAULT_GRID), 0.0), "distance_m"),
    ],
)
def test_bad_component_parameters_raise_clear_errors(make, message):
    with pytest.raises(InputError, match=message):
        make()


@pytest.mark.parametrize("lamp", [HMILamp(), QTHLamp(), PhosphorWhiteLED()], ids=type)
@pytest.mark.parametrize(("t0", "exposure"), [(0.0123, 0.0517), (0.2, 0.004), (1.0, 0.5)])
def test_every_lamp_is_the_sum_of_its_parts_over_an_exposure(lamp, t0, exposure):
    # Independent of the parts: adaptive quadrature of the instantaneous output (flicker and
    # drift included) over [t0, t0 + exposure].
    numeric = integrate.quad_vec(
        lambda t: lamp.intensity(DEFAULT_GRID, t).values, t0, t0 + exposure, epsrel=1e-10
    )[0]
    parts = lamp.spectral_parts(DEFAULT_GRID)
    weights = lamp.part_exposure_s(t0, exposure)
    assert parts.values.shape == (weights.size, 33)
    integral = lamp.exposure_integral(DEFAULT_GRID, t0, exposure).values
    # The drift is taken at the window's middle: far below 1e-6 relative over half a second.
    np.testing.assert_allclose(integral, numeric, rtol=1e-6)
    np.testing.assert_allclose(integral, weights @ parts.values, rtol=1e-12)
    # At switch-on (no drift yet, flicker phase 0) the parts add up to the intensity.
    np.testing.assert_allclose(
        parts.values.sum(axis=0), lamp.intensity(DEFAULT_GRID, 0.0).values, rtol=1e-12
    )


def test_exposure_integral_scales_with_exposure_time():
    for lamp in (QTHLamp(), PhosphorWhiteLED(), HMILamp(drift_fraction=0.0)):
        # Whole flicker periods (1/15 s) so that the HMI lines average out too.
        short = lamp.exposure_integral(DEFAULT_GRID, 0.0, 1 / 15).values
        long = lamp.exposure_integral(DEFAULT_GRID, 0.0, 20 / 15).values
        np.testing.assert_allclose(long, 20 * short, rtol=1e-9)
