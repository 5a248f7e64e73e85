"""EMVA 1288 measurements shaped like the official reference sets 002 and 003
(``scripts/emva1288_reference_sets.py``): read and analysed as the emva1288 package reads them,
fitted, and repeated by the fitted twin.

- set 002's plan (8 bit, exposure-0 steps, 100 frames per spatial step) taken by a twin camera of
  known parameters whose dark frames are limited by quantization (read noise 0.2 DN): the fit
  must recover the camera, and the figures EMVA 1288 computes from quantized frames;
- set 003's simulated camera (12 bit, one exposure time, patterns the twin does not model): the
  fitted twin must give the same figures.

The twin's figures are compared with the real ones within what EMVA 1288 asks of a model
(5 %; PRNU and DSNU 15 %). The package's own reading of the same files (its parser, loader and
saturation search) is the peer of spectwin's analysis.
"""

from __future__ import annotations

import shutil
from dataclasses import replace

import pytest

from recon.emva.analysis import analyse_measurement, run_results1288
from recon.emva.descriptor import DESCRIPTOR_NAME, write_descriptor
from recon.emva.fit import fit_sensor
from twin.rigs.fitted_camera import write_fitted_camera
from twin.studies.emva_twin import run_emva_comparison


def _round_trip(measurement, folder):
    """(analysis, fit, comparison): the measurement fitted as ``spectwin camera fit`` does, and
    repeated by the fitted camera as ``spectwin camera CAMERA --emva`` does."""
    analysis = analyse_measurement(measurement.path)
    fitted = fit_sensor(analysis, wavelength_nm=550.0)
    camera = folder / "fitted.yaml"
    write_fitted_camera(fitted, camera, name="fitted", serial="FITTED-1288", pixel_pitch_um=5.0)
    return analysis, fitted, run_emva_comparison(camera, folder / "twin", seed=11)


@pytest.fixture(scope="module")
def cmos8_round_trip(cmos8_measurement, tmp_path_factory):
    return _round_trip(cmos8_measurement, tmp_path_factory.mktemp("cmos8_round_trip"))


@pytest.fixture(scope="module")
def heidelberg_round_trip(heidelberg_measurement, tmp_path_factory):
    return _round_trip(heidelberg_measurement, tmp_path_factory.mktemp("heidelberg_round_trip"))


@pytest.fixture(params=["cmos8_round_trip", "heidelberg_round_trip"])
def round_trip(request):
    """Each measurement's round trip, in turn (parametrizes the test)."""
    return request.getfixturevalue(request.param)


@pytest.mark.parametrize(
    ("figure", "tolerance"),
    [
        ("system_gain_dn_per_e", 0.05),
        ("dark_noise_dn", 0.05),
        ("quantum_efficiency_percent", 0.05),
        ("saturation_capacity_photons", 0.05),
        ("dsnu_e", 0.15),
        ("prnu_percent", 0.15),
    ],
)
def test_the_fitted_twin_repeats_the_figures(round_trip, figure, tolerance):
    _, _, comparison = round_trip
    row = comparison["figures"][figure]
    assert row["twin"] == pytest.approx(row["real"], rel=tolerance), figure


def test_the_fit_recovers_the_8bit_camera_under_its_quantized_frames(
    cmos8_round_trip, emva_reference_sets
):
    """The dark frames are not dithered: the package reports the floor of 0.49 DN as dark
    noise and quantized spatial variances; the fit finds the camera behind them."""
    analysis, fitted, _ = cmos8_round_trip
    truth = emva_reference_sets.CMOS_8BIT
    assert analysis.dark_noise_dn == pytest.approx(0.49, abs=0.001)  # the package's floor
    recovered = {
        "system gain": (fitted.system_gain_dn_per_e, truth["system_gain_dn_per_e"], 0.02),
        "quantum efficiency": (fitted.quantum_efficiency, 0.5, 0.02),
        "read noise": (fitted.read_noise_dn, truth["read_noise_dn"], 0.05),
        "offset": (fitted.adc_offset_dn, truth["adc_offset_dn"], 0.005),
        "offset DSNU": (fitted.offset_sigma_dn, 0.25, 0.05),
        "PRNU": (fitted.prnu, truth["fixed_pattern"]["prnu_sigma"], 0.05),
    }
    for parameter, (value, expected, tolerance) in recovered.items():
        assert value == pytest.approx(expected, rel=tolerance), parameter
    assert fitted.saturated_by == "ADC"


def test_the_heidelberg_camera_fits_at_its_one_exposure_time(
    heidelberg_round_trip, emva_reference_sets
):
    """One exposure time: no dark current is measured and the offset is the dark mean (a
    straight line through one exposure time has no intercept)."""
    _, fitted, _ = heidelberg_round_trip
    truth = emva_reference_sets.HEIDELBERG
    assert fitted.exposure_range_s == (1e-3, 1e-3)
    assert fitted.adc_offset_dn == pytest.approx(truth["offset_dn"], abs=0.1)
    assert fitted.read_noise_dn == pytest.approx(truth["dark_noise_dn"], rel=0.03)
    assert fitted.system_gain_dn_per_e == pytest.approx(truth["system_gain_dn_per_e"], rel=0.03)
    assert fitted.dark_current_e_per_s == 0.0


def test_the_emva1288_package_reads_the_same_files_alike(round_trip):
    """The package's own parser, image loader and saturation search, on the same files."""
    from emva1288.process import Data1288, LoadImageData, ParseEmvaDescriptorFile

    analysis, _, _ = round_trip
    parser = ParseEmvaDescriptorFile(str(analysis.descriptor.path), loglevel=40)
    data = Data1288(LoadImageData(parser.images, loglevel=40).data, loglevel=40)
    package = run_results1288(data.data)
    assert package.index_u_ysat == analysis.transfer.saturation_index
    peer = {
        "K": (package.K, analysis.system_gain_dn_per_e),
        "QE": (package.QE / 100, analysis.quantum_efficiency),
        "dark noise": (package.sigma_y_dark, analysis.dark_noise_dn),
        "saturation": (package.u_p_sat, analysis.saturation_photons),
        "DSNU": (package.DSNU1288, analysis.dsnu_e),
        "PRNU": (package.PRNU1288, analysis.prnu_percent),
    }
    for figure, (theirs, ours) in peer.items():
        assert ours == pytest.approx(theirs, rel=1e-9), figure


def test_a_plan_ending_at_saturation_still_shows_the_adc_clip(cmos8_measurement, tmp_path):
    """Set 002's plan cut one step after the variance peak: the mean never reaches the ADC's
    top (255 DN), yet the peak is where the ADC's top puts it, so the ADC clips first."""
    folder = tmp_path / "cut"
    shutil.copytree(cmos8_measurement.path.parent, folder)
    full = analyse_measurement(folder / DESCRIPTOR_NAME)
    last_ns = full.transfer.exposure_s[full.transfer.saturation_index + 1] * 1e9
    steps = tuple(s for s in full.descriptor.steps if s.spatial or s.exposure_ns <= last_ns)
    write_descriptor(replace(full.descriptor, steps=steps))
    analysis = analyse_measurement(folder / DESCRIPTOR_NAME)
    assert analysis.transfer.mean_dn.max() < 250
    fitted = fit_sensor(analysis, wavelength_nm=550.0)
    assert fitted.saturated_by == "ADC"
    assert analysis.saturation_photons == full.saturation_photons
