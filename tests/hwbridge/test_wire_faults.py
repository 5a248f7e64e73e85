"""Bad replies on the wire, the same for every serial driver of the dome: garbled bytes, an answer
to another question, silence and the wrong device each give a one-line error of
``hwbridge.errors``, and a failed ``stage`` leaves no port open."""

import pytest

from hwbridge.drivers.apt_rotation_stage import AptRotationStage
from hwbridge.drivers.dmx_led_array import DmxLedArray
from hwbridge.errors import DeviceError, DeviceTimeout


def _stage(options):
    pytest.importorskip("thorlabs_apt_protocol")  # the driver's extra
    return AptRotationStage(f"apt://?{options}", timeout_s=0.2)


def _leds(options):
    return DmxLedArray(f"dmxusbpro://?{options}", timeout_s=0.2)


@pytest.mark.parametrize(
    ("device", "options", "error", "message"),
    [
        (_stage, "garble=1", DeviceError, r"garbled bytes where MGMSG_HW_GET_INFO was expected"),
        (_stage, "wrong_reply=1", DeviceError, r"expected MGMSG_HW_GET_INFO, got mot_get_poscount"),
        (_stage, "silent=1", DeviceTimeout, r"no MGMSG_HW_GET_INFO within 0.2 s"),
        (_stage, "model=KDC101", DeviceError, r"is a 'KDC101', expected a K10CR1"),
        (_leds, "garble=1", DeviceError, r"garbled answer to Get Widget Serial Number"),
        (_leds, "wrong_label=1", DeviceError, r"expected the Get Widget Serial Number reply \("),
        (_leds, "silent=1", DeviceTimeout, r"no complete answer to Get Widget Serial Number"),
    ],
)
def test_bad_replies_give_one_line_errors(device, options, error, message):
    driver = device(options)
    with pytest.raises(error, match=message) as raised:
        driver.stage()
    assert "\n" not in str(raised.value)
    with pytest.raises(DeviceError, match="not staged"):
        driver.read()
