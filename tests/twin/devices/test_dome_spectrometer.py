"""The simulated dome spectrometer reads the white standard's radiance under the LEDs on, with
the noise of a reading that peaks at its set count, the same noise for the same plan step."""

import numpy as np
import pytest

from hwbridge.protocols import LampMonitor
from recon.calibration.dome_lighting import led_irradiance
from twin.components.lamps import PhosphorWhiteLED
from twin.components.targets import zenith_white_reflectance
from twin.devices.dome_spectrometer import (
    PEAK_COUNTS,
    SPECTROMETER_GRID,
    DomeSpectrometer,
    SimDomeSpectrometer,
)
from twin.devices.sim_devices import VirtualRig

LEDS = np.array([[0.0, 0.0, 0.5], [0.3, 0.0, 0.4]])


def _reading(rig: VirtualRig, spectrometer: DomeSpectrometer) -> np.ndarray:
    device = spectrometer.on_rig(rig)
    device.trigger()
    ((_, entry),) = device.read().items()
    return np.asarray(entry["value"])


def _lit(pattern, current_ma=700.0, seed=0, frames_taken=1) -> VirtualRig:
    rig = VirtualRig(seed=seed, led_pattern=np.array(pattern, bool), led_current_ma=current_ma)
    rig.frames_taken = frames_taken
    return rig


def test_a_reading_is_the_white_standards_radiance_within_its_shot_noise():
    spectrometer = DomeSpectrometer.of_dome(LEDS, 700.0)
    reading = _reading(_lit([True, True]), spectrometer)
    irradiance = led_irradiance(np.zeros(3), LEDS).sum()
    expected = (
        zenith_white_reflectance(SPECTROMETER_GRID).values
        * PhosphorWhiteLED().intensity(SPECTROMETER_GRID).values
        * irradiance
        / np.pi
    )
    relative = (reading - expected) / expected.max()
    # counts at the peak are PEAK_COUNTS: shot noise 1/sqrt(PEAK_COUNTS) of the peak there
    assert np.abs(relative).max() < 5 / np.sqrt(PEAK_COUNTS)
    assert 0.5 / np.sqrt(PEAK_COUNTS) < relative.std() < 1.5 / np.sqrt(PEAK_COUNTS)


def test_half_the_current_halves_the_reading_and_the_step_sets_the_noise():
    spectrometer = DomeSpectrometer.of_dome(LEDS, 700.0)
    full = _reading(_lit([True, False]), spectrometer)
    half = _reading(_lit([True, False], current_ma=350.0), spectrometer)
    assert half.sum() / full.sum() == pytest.approx(0.5, rel=1e-3)
    np.testing.assert_array_equal(full, _reading(_lit([True, False]), spectrometer))
    assert not np.array_equal(full, _reading(_lit([True, False], frames_taken=2), spectrometer))
    assert not np.array_equal(full, _reading(_lit([True, False], seed=1), spectrometer))


def test_it_is_a_lamp_monitor_and_refuses_a_read_before_a_trigger():
    device = SimDomeSpectrometer(_lit([True, False]), DomeSpectrometer.of_dome(LEDS, 700.0))
    assert isinstance(device, LampMonitor) and device.samples == SPECTROMETER_GRID.size
    with pytest.raises(ValueError, match="trigger"):
        device.read()
