"""One contract per device kind, kept by the simulated device and by the real driver on its wire
emulator: the tunable filter, the camera, and the dome's rotation stage and LED array (the real
drivers also through a pseudo-terminal)."""

import contextlib

import numpy as np
import pytest

from hwbridge.drivers.varispec import VariSpec
from hwbridge.errors import DeviceError
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
    try:
        camera.set_exposure(0.05)
        exposure_s = 0.05
    except DeviceError as refused:  # the simulated producer's camera has no exposure to set
        assert "has no ExposureTime feature" in str(refused)
        exposure_s = None
    frame, metadata = camera.snap()
    assert frame.dtype.name == "uint16" and frame.shape == camera.frame_shape
    assert metadata["exposure_s"] == exposure_s and metadata["timestamp"] > 0
    (description,) = camera.describe().values()
    assert description["shape"] == list(camera.frame_shape) and description["units"] == "DN"


def test_camera_refuses_a_negative_exposure(camera):
    with pytest.raises(ValueError, match="exposure"):
        camera.set_exposure(-1.0)


# -- the dome: rotation stage and LED array, simulated and real drivers on their emulators ----


@pytest.fixture(params=["simulated", "apt-emulator", "apt-emulator-on-a-terminal"])
def rotation_stage(request):
    from hwbridge.drivers.apt_rotation_stage import AptRotationStage
    from hwbridge.emulators.apt_stage_state import AptStageState
    from hwbridge.emulators.pty_link import EmulatorPty
    from twin.devices.sim_devices import SimRotationStage

    if request.param != "simulated":
        pytest.importorskip("thorlabs_apt_protocol")  # the driver's extra
    with contextlib.ExitStack() as stack:
        if request.param == "simulated":
            device = SimRotationStage(VirtualRig())
        elif request.param == "apt-emulator":
            device = AptRotationStage("apt://?speed=36000")
        else:
            path = stack.enter_context(EmulatorPty(AptStageState(speed_deg_s=36000.0)))
            device = AptRotationStage(path, timeout_s=5.0)
        device.stage()
        stack.callback(device.unstage)
        yield device


@pytest.fixture(params=["simulated", "dmx-emulator", "dmx-emulator-on-a-terminal"])
def led_array(request):
    from hwbridge.drivers.dmx_led_array import DmxLedArray
    from hwbridge.emulators.dmx_usb_pro_state import DmxUsbProState
    from hwbridge.emulators.pty_link import EmulatorPty
    from twin.devices.sim_devices import SimLedArray

    with contextlib.ExitStack() as stack:
        if request.param == "simulated":
            device = SimLedArray(VirtualRig(), 198)
        elif request.param == "dmx-emulator":
            device = DmxLedArray("dmxusbpro://")
        else:
            path = stack.enter_context(EmulatorPty(DmxUsbProState()))
            device = DmxLedArray(path, timeout_s=5.0)
        device.stage()
        stack.callback(device.unstage)
        yield device


def test_rotation_stage_turns_to_an_angle_and_reports_it(rotation_stage):
    from hwbridge.protocols import RotationStage

    assert isinstance(rotation_stage, RotationStage)
    assert rotation_stage.range_deg == (0.0, 360.0) and rotation_stage.step_deg == 15.0
    for angle in (0.0, 15.0, 92.5, 345.0, 360.0):
        rotation_stage.set({"angle_deg": angle})
        (reading,) = rotation_stage.read().values()
        assert reading["value"] == pytest.approx(angle, abs=1e-5) and reading["timestamp"] > 0
    rotation_stage.set({"view_id": 3})  # stage position 3 of a plan
    (reading,) = rotation_stage.read().values()
    assert reading["value"] == pytest.approx(45.0, abs=1e-5)
    assert rotation_stage.describe().keys() == rotation_stage.read().keys()
    (description,) = rotation_stage.describe().values()
    assert description["units"] == "deg" and description["dtype"] == "number"


@pytest.mark.parametrize(
    ("target", "message"),
    [
        ({"angle_deg": -0.5}, "outside"),
        ({"angle_deg": 360.5}, "outside"),
        ({"angle_deg": float("nan")}, "outside"),
        ({"view_id": 25}, "outside"),
        ({"azimuth_deg": 10.0}, "angle_deg"),
    ],
)
def test_rotation_stage_refuses_what_it_cannot_reach(rotation_stage, target, message):
    rotation_stage.set({"angle_deg": 30.0})
    with pytest.raises(ValueError, match=message):
        rotation_stage.set(target)
    (reading,) = rotation_stage.read().values()
    assert reading["value"] == pytest.approx(30.0, abs=1e-5)  # it did not move


def test_led_array_switches_one_led_at_a_current_all_and_none(led_array):
    from hwbridge.protocols import LedArray

    assert isinstance(led_array, LedArray)
    assert led_array.count == 198 and led_array.current_range_ma[1] == 700.0
    tolerance = led_array.current_step_ma / 2 + 1e-9
    led_array.light(7, 350.0)
    (reading,) = led_array.read().values()
    currents = reading["value"]
    assert currents.shape == (198,) and np.flatnonzero(currents) == [7]
    assert currents[7] == pytest.approx(350.0, abs=tolerance)
    led_array.light(197)  # at the drive current, full scale by default
    (reading,) = led_array.read().values()
    assert np.flatnonzero(reading["value"]) == [197] and reading["value"][197] == 700.0
    led_array.set(np.ones(198, bool), 100.0)
    (reading,) = led_array.read().values()
    np.testing.assert_allclose(reading["value"], 100.0, atol=tolerance)
    led_array.set(np.zeros(198, bool))
    (reading,) = led_array.read().values()
    assert not reading["value"].any()
    assert led_array.describe().keys() == led_array.read().keys()
    (description,) = led_array.describe().values()
    assert description["units"] == "mA" and description["shape"] == [198]


@pytest.mark.parametrize(
    ("request_", "message"),
    [
        (lambda leds: leds.light(198), "LED 198"),
        (lambda leds: leds.light(-1), "LED -1"),
        (lambda leds: leds.light(3, 0.0), "positive LED current"),
        (lambda leds: leds.light(3, -5.0), "positive LED current"),
        (lambda leds: leds.light(3, 701.0), "current 701 mA is outside"),
        (lambda leds: leds.set(np.ones(5, bool)), "198 LEDs"),
    ],
)
def test_led_array_refuses_leds_and_currents_it_does_not_have(led_array, request_, message):
    led_array.light(7, 350.0)
    with pytest.raises(ValueError, match=message):
        request_(led_array)
    (reading,) = led_array.read().values()
    assert np.flatnonzero(reading["value"]) == [7]  # unchanged
