"""Fitting twin cameras to EMVA 1288 measurements (recon.emva.fit, twin.rigs.fitted_camera):
a camera of known parameters recovered from its simulated measurement, and the shipped Basler
camera as the fit of the shipped real measurement."""

from pathlib import Path

import numpy as np
import pytest

from recon.emva.analysis import analyse_measurement
from recon.emva.fit import fit_sensor
from recon.measured_data import data_path
from twin.rigs.camera_config import load_camera_config
from twin.rigs.fitted_camera import write_fitted_camera

BASLER = "real/emva1288_basler_ccd12/EMVA1288_Data.txt"
BASLER_SOURCE = (
    "recon/data/real/emva1288_basler_ccd12 (EMVA1288/datasets "
    "EMVA1288_ReferenceSet_001_CCD_12Bit, Basler AG 2011, CC BY-SA 3.0)"
)
SHIPPED = Path(__file__).resolve().parents[2] / "scenes" / "cameras" / "basler_ccd12.yaml"


def test_the_fit_recovers_a_known_camera_from_its_simulated_measurement(
    tmp_path, make_emva_measurement, synthetic_camera
):
    measurement = make_emva_measurement(tmp_path)
    fitted = fit_sensor(analyse_measurement(measurement.path), wavelength_nm=550.0)
    truth = synthetic_camera
    recovered = {
        "system gain": (fitted.system_gain_dn_per_e, truth.system_gain_dn_per_e),
        "quantum efficiency": (fitted.quantum_efficiency, truth.quantum_efficiency.peak_qe),
        "read noise": (fitted.read_noise_dn, truth.read_noise_dn),
        "offset": (fitted.adc_offset_dn, truth.adc_offset_dn),
        "full well": (fitted.full_well_e, truth.full_well_e),
        "dark current": (fitted.dark_current_e_per_s, truth.dark_current.e_per_s_at_reference),
        "offset DSNU": (fitted.offset_sigma_dn, truth.fixed_pattern.offset_sigma_dn),
        "PRNU": (fitted.prnu, truth.fixed_pattern.prnu_sigma),
        "OECF knee": (fitted.knee_strength, truth.oecf.strength),
    }
    for name, (value, expected) in recovered.items():
        assert value == pytest.approx(expected, rel=0.03), name
    assert fitted.saturated_by == "full well"
    # The knee is needed: a straight line misses the means by far more than the knee does.
    assert fitted.straight_line_rms_percent > 5 * fitted.knee_rms_percent


def test_the_shipped_basler_camera_is_the_fit_of_the_shipped_measurement(tmp_path):
    fitted = fit_sensor(analyse_measurement(data_path(BASLER)), wavelength_nm=550.0)
    shipped = load_camera_config("basler_ccd12")
    written = tmp_path / "basler_ccd12.yaml"
    regenerated = write_fitted_camera(
        fitted,
        written,
        name=shipped.name,
        serial=shipped.serial,
        pixel_pitch_um=shipped.pixel_pitch_um,
        source=BASLER_SOURCE,
    )
    assert regenerated == shipped
    assert written.read_text() == SHIPPED.read_text()
    assert shipped.emva1288.descriptor_path() == data_path(BASLER)
    # The real camera clips at its ADC's top (4095 DN in every pixel of the brightest steps).
    assert fitted.saturated_by == "ADC" and fitted.analysis.transfer.mean_dn.max() == 4095


def test_the_numpy_2_shim_leaves_numpy_alone():
    analyse_measurement(data_path(BASLER))
    if int(np.__version__.split(".")[0]) >= 2:
        assert not hasattr(np, "asfarray")
