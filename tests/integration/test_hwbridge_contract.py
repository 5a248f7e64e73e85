"""One contract for every TunableFilter: the simulated one and the real driver on its emulator."""

import pytest

from hwbridge.drivers.varispec import VariSpec
from hwbridge.protocols import TunableFilter
from twin.devices.sim_devices import SimTunableFilter, VirtualRig


@pytest.fixture(params=["simulated", "varispec-emulator"])
def tunable_filter(request):
    device = (
        SimTunableFilter(VirtualRig())
        if request.param == "simulated"
        else VariSpec("varispec://?settle_ms=1")
    )
    device.stage()
    yield device
    device.unstage()


def test_is_a_tunable_filter(tunable_filter):
    assert isinstance(tunable_filter, TunableFilter)
    assert tunable_filter.range_nm == (400.0, 720.0)


def test_set_then_read_reports_the_band(tunable_filter):
    for band in (400.0, 550.0, 720.0):
        tunable_filter.set(band)
        (reading,) = tunable_filter.read().values()
        assert reading["value"] == band and reading["timestamp"] > 0


def test_describe_matches_read(tunable_filter):
    tunable_filter.set(500.0)
    assert tunable_filter.describe().keys() == tunable_filter.read().keys()
    (description,) = tunable_filter.describe().values()
    assert description["units"] == "nm" and description["dtype"] == "number"


@pytest.mark.parametrize("band", [399.0, 721.0])
def test_out_of_range_is_a_value_error(tunable_filter, band):
    with pytest.raises(ValueError, match="outside"):
        tunable_filter.set(band)


@pytest.fixture(params=["simulated", "genicam-simulated-producer"])
def camera(request):
    if request.param == "simulated":
        import numpy as np

        from twin.components.lamps import HMILamp
        from twin.devices.sim_devices import SimCamera
        from twin.gonio.signals import WhiteReferenceSignal
        from twin.sensor.model import Sensor

        rig = VirtualRig(band_nm=550.0)
        sensor = Sensor("coolsnap_k4", roi=(16, 16))
        device = SimCamera(rig, sensor, WhiteReferenceSignal(sensor, HMILamp()), np.zeros(1))
    else:
        genicam_camera = pytest.importorskip("hwbridge.drivers.genicam_camera")
        device = genicam_camera.GenICamCamera(genicam_camera.simulated_producer())
    device.stage()
    yield device
    device.unstage()


def test_camera_snaps_uint16_frames_of_its_shape(camera):
    from hwbridge.protocols import Camera

    assert isinstance(camera, Camera)
    camera.set_exposure(0.05)
    frame, metadata = camera.snap()
    assert frame.dtype.name == "uint16" and frame.shape == camera.frame_shape
    assert metadata["exposure_s"] == 0.05 and metadata["timestamp"] > 0
    (description,) = camera.describe().values()
    assert description["shape"] == list(camera.frame_shape) and description["units"] == "DN"


def test_camera_refuses_a_negative_exposure(camera):
    with pytest.raises(ValueError, match="exposure"):
        camera.set_exposure(-1.0)
