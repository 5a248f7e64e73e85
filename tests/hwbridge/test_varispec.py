"""The VariSpec driver against its wire emulator (real bytes through pyserial)."""

import time

import pytest

from hwbridge.drivers.varispec import VariSpec
from hwbridge.emulators.varispec_state import VariSpecState
from hwbridge.errors import DeviceDisconnected, DeviceError, InputError
from hwbridge.protocols import TunableFilter


@pytest.fixture
def lctf():
    device = VariSpec("varispec://?settle_ms=30")
    device.stage()
    yield device
    device.unstage()


def test_the_wire_protocol_bytes():
    state = VariSpecState(initialized=True)
    assert state.respond(b"V?\r") == b"V?\rV 1.37 400.000 720.000 10218\r"
    assert state.respond(b"W 550.000\r") == b"W 550.000\r"
    assert state.respond(b"W?\r") == b"W?\rW 550.000\r"
    assert state.respond(b"@") == b"@\x03"
    assert state.respond(b"!") == b"!<"  # still settling
    time.sleep(0.06)
    assert state.respond(b"!") == b"!>"
    assert state.respond(b"W 800\r") == b"W 800\r"
    assert state.respond(b"@") == b"@\x23" and state.respond(b"W?\r") == b"W?\rW*\r"
    assert state.respond(b"R?\r") == b"R?\rR 3\r" and state.respond(b"R1\r") == b"R1\r"
    assert state.respond(b"@") == b"@\x03"


def test_stage_initializes_and_reads_the_range(lctf):
    assert isinstance(lctf, TunableFilter)
    assert lctf.range_nm == (400.0, 720.0)
    assert lctf.status() == {"initialized": True, "exercised": True, "error": False}
    assert "10218" in lctf.describe()["lctf_wavelength_nm"]["source"]


def test_set_waits_for_the_crystals_and_query_reads_back(lctf):
    started = time.monotonic()
    lctf.set(550.0)
    assert time.monotonic() - started >= 0.03  # waited for the 30 ms settling
    assert not lctf.busy()
    assert lctf.wavelength_nm() == 550.0
    assert lctf.read()["lctf_wavelength_nm"]["value"] == 550.0
    for band in range(400, 721, 40):
        lctf.set(float(band))
        assert lctf.wavelength_nm() == band


def test_out_of_range_is_refused_before_it_reaches_the_wire(lctf):
    with pytest.raises(InputError, match="outside the filter's range 400.0-720.0"):
        lctf.set(750.0)
    assert lctf.status()["error"] is False


def test_controller_errors_are_read_cleared_and_raised():
    device = VariSpec("varispec://?settle_ms=1&longest=700")
    device.stage()
    device._range_nm = (400.0, 720.0)  # a wrong belief about the range: the controller objects
    with pytest.raises(DeviceError, match="error 3"):
        device.set(710.0)
    assert device.status()["error"] is False  # R1 cleared it
    device.unstage()


def test_unexpected_replies_give_clear_errors():
    device = VariSpec("varispec://?garble=1")
    with pytest.raises(DeviceError, match="echoed"):
        device.stage()
    with pytest.raises(DeviceError, match="not staged"):
        VariSpec("varispec://").set(500.0)
    with pytest.raises(DeviceDisconnected, match="cannot open .*unknown"):
        VariSpec("varispec://?colour=red").stage()
