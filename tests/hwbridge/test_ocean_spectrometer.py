"""The Ocean Optics driver: clear errors without hardware; a real device test is opt-in."""

import numpy as np
import pytest

from hwbridge.drivers.ocean_spectrometer import OceanSpectrometer
from hwbridge.errors import DeviceError, InputError
from hwbridge.protocols import Spectrometer

# The driver imports seabreeze only when it stages a device: skip here without the extra.
pytest.importorskip("seabreeze")


def test_without_a_device_the_driver_says_so():
    monitor = OceanSpectrometer()
    assert isinstance(monitor, Spectrometer)
    with pytest.raises(DeviceError, match="not staged"):
        monitor.trigger()
    with pytest.raises(DeviceError, match="no spectrum yet"):
        monitor.read()
    with pytest.raises(InputError, match="integration_s"):
        OceanSpectrometer(integration_s=0)


@pytest.mark.hardware
def test_a_connected_spectrometer_returns_a_spectrum():
    monitor = OceanSpectrometer()
    monitor.stage()
    monitor.trigger()
    reading = monitor.read()
    wavelengths = reading["monitor_wavelengths_nm"]["value"]
    assert np.all(np.diff(wavelengths) > 0) and len(reading["monitor_counts"]["value"]) == len(
        wavelengths
    )
    monitor.unstage()
