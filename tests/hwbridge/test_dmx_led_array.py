"""The DMX LED-array driver against the emulated Enttec DMX USB Pro and its LED decoders (real
bytes through pyserial, and through a pseudo-terminal)."""

import numpy as np
import pytest

from hwbridge.drivers.dmx_led_array import DmxLedArray
from hwbridge.emulators.dmx_usb_pro_state import DmxUsbProState
from hwbridge.emulators.pty_link import EmulatorPty
from hwbridge.errors import DeviceDisconnected, DeviceTimeout, InputError

FULL_SCALE_MA = 700.0


def test_the_emulator_answers_the_documented_bytes():
    widget = DmxUsbProState(serial_number="02015678")
    # Get Widget Serial Number (label 10): 4 bytes of BCD, least significant first.
    assert widget.respond(bytes.fromhex("7e0a0000e7")) == bytes.fromhex("7e0a040078560102e7")
    # Get Widget Parameters (label 3, no user configuration): firmware 1.44 (LSB, MSB), break
    # 9 x 10.67 us, mark after break 1 x 10.67 us, 40 packets/s.
    assert widget.respond(bytes.fromhex("7e0302000000e7")) == bytes.fromhex("7e0305002c01090128e7")
    # Output Only Send DMX Packet (label 6): start code 0, then slots 1..198; slot 31 at 128.
    slots = bytearray(198)
    slots[30] = 128
    packet = bytes([0x7E, 6]) + (199).to_bytes(2, "little") + b"\0" + slots + b"\xe7"
    assert widget.respond(packet) == b"" and widget.transmitting
    currents = widget.output_currents_ma()
    assert currents.shape == (9, 24) and np.flatnonzero(currents) == [30]
    assert currents[1, 6] == pytest.approx(128 / 255 * FULL_SCALE_MA)  # LED 30: decoder 1, out 6
    widget.respond(bytes.fromhex("7e0302000000e7"))
    assert widget.transmitting  # Get Widget Parameters keeps the DMX output running
    widget.respond(bytes.fromhex("7e0a0000e7"))
    assert not widget.transmitting and currents[1, 6] > 0  # the decoders hold their outputs
    assert widget.respond(bytes.fromhex("7e0302000000")) == b""  # no end byte: dropped


@pytest.fixture
def widget():
    state = DmxUsbProState()
    with EmulatorPty(state) as path:
        leds = DmxLedArray(path, timeout_s=5.0)
        leds.stage()
        yield leds, state
        leds.unstage()


def test_stage_reads_the_widget_and_switches_every_led_off(widget):
    leds, state = widget
    assert leds.widget == {
        "serial": "02015678",
        "firmware": "1.44",
        "break_us": 96.0,
        "mark_after_break_us": 10.7,
        "packets_per_s": 40,
    }
    assert state.transmitting and not state.output_currents_ma().any()
    assert "DMX USB Pro 02015678" in leds.describe()["leds_current_ma"]["source"]


def test_each_led_reaches_its_decoder_output_at_its_current(widget):
    leds, state = widget
    for led, decoder, output in [(0, 0, 0), (30, 1, 6), (197, 8, 5)]:
        leds.light(led, 350.0)
        currents = state.output_currents_ma()
        assert np.flatnonzero(currents) == [decoder * 24 + output]
        assert currents[decoder, output] == pytest.approx(128 / 255 * FULL_SCALE_MA)  # 8 bits
    np.testing.assert_allclose(leds.read()["leds_current_ma"]["value"], currents.ravel()[:198])
    leds.set(np.ones(198, bool))  # the alignment frame: all at the drive current
    assert np.all(state.output_currents_ma().ravel()[:198] == FULL_SCALE_MA)
    leds.set(np.zeros(198, bool))
    assert not state.output_currents_ma().any() and state.transmitting


def test_leds_start_at_the_first_address_of_the_decoders():
    leds = DmxLedArray("dmxusbpro://?first_address=101", count=198, first_address=101)
    leds.stage()
    leds.light(0)
    state = leds._port.state
    assert np.flatnonzero(state.universe) == [100]  # slot 101
    assert state.output_currents_ma()[0, 0] == FULL_SCALE_MA
    leds.unstage()


def test_a_widget_that_stops_answering_is_caught_at_the_next_change():
    leds = DmxLedArray("dmxusbpro://", timeout_s=0.2)
    leds.stage()
    leds._port.state.silent = True  # unplugged: DMX sends no answer, only the widget does
    with pytest.raises(DeviceTimeout, match="no complete answer to Get Widget Parameters"):
        leds.light(5)
    (currents,) = leds.read().values()
    assert not currents["value"].any()  # what the widget last acknowledged: all off
    leds.unstage()


def test_out_of_range_requests_are_refused_before_the_wire():
    leds = DmxLedArray("dmxusbpro://")
    leds.stage()
    state = leds._port.state
    for request, message in [
        (lambda: leds.light(198), r"LED 198 is not in 0..197"),
        (lambda: leds.light(-1), r"LED -1 is not in 0..197"),
        (lambda: leds.light(3, 701.0), r"current 701 mA is outside .* 2.745-700 mA"),
        (lambda: leds.light(3, 1.0), r"current 1 mA is outside"),  # below one DMX step
        (lambda: leds.light(3, 0.0), r"expected a positive LED current"),
        (lambda: leds.set(np.ones(5, bool)), r"pattern of 198 LEDs, got shape \(5,\)"),
    ]:
        with pytest.raises(InputError, match=message):
            request()
    assert not state.output_currents_ma().any()
    with pytest.raises(InputError, match="do not fit the 512 slots"):
        DmxLedArray("dmxusbpro://", count=198, first_address=400)
    with pytest.raises(DeviceDisconnected, match="cannot open .*unknown"):
        DmxLedArray("dmxusbpro://?colour=red").stage()
    leds.unstage()
