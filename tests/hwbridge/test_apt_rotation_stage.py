"""The Thorlabs APT rotation-stage driver against its wire emulator (real bytes through pyserial,
and through a pseudo-terminal)."""

import struct
import sys
import time

import pytest

from hwbridge.drivers.apt_rotation_stage import K10CR1_COUNTS_PER_DEG, AptRotationStage
from hwbridge.emulators.apt_stage_state import AptStageState
from hwbridge.emulators.pty_link import EmulatorPty
from hwbridge.errors import (
    DeviceDisconnected,
    DeviceError,
    DeviceTimeout,
    DriverNotInstalled,
    InputError,
    Remedy,
)

# The driver imports its protocol library only when it stages: skip here without the extra.
apt = pytest.importorskip("thorlabs_apt_protocol")

STAGE, HOST = 0x50, 0x01
FIFTEEN_DEG = 2048000  # 15 deg of the K10CR1: 15 * 409600 / 3 microsteps


def test_the_library_writes_the_documented_bytes():
    # Header: message id (LE), two parameters, destination, source; long form: length (LE) and
    # bit 7 of the destination set, then the data.
    assert round(15 * K10CR1_COUNTS_PER_DEG) == FIFTEEN_DEG
    assert apt.hw_req_info(STAGE, HOST) == bytes.fromhex("050000005001")
    assert apt.mot_move_home(STAGE, HOST, 1) == bytes.fromhex("430401005001")
    assert apt.mot_move_absolute(STAGE, HOST, 1, FIFTEEN_DEG) == bytes.fromhex(
        "53040600d001"
    ) + struct.pack("<Hl", 1, FIFTEEN_DEG)


def test_the_emulator_answers_the_documented_bytes():
    state = AptStageState(speed_deg_s=0.01, homed=True)  # a 15 deg move takes 1500 s
    info = state.respond(bytes.fromhex("050000005001"))
    assert info[:6] == bytes.fromhex("060054008150") and len(info) == 6 + 84
    assert info[10:18] == b"K10CR1\0\0"
    assert state.respond(bytes.fromhex("100201015001")) == b""  # enable channel 1
    started = time.monotonic()
    assert state.respond(bytes.fromhex("53040600d001") + struct.pack("<Hl", 1, FIFTEEN_DEG)) == b""
    sent = time.monotonic()
    moving = state.respond(bytes.fromhex("800401005001"))  # status update, mid-move
    assert moving[:6] == bytes.fromhex("81040e008150")
    _, position, encoder, bits = struct.unpack("<HllL", moving[6:])
    assert 0 <= position < FIFTEEN_DEG and encoder == 0
    assert bits == 0x80000000 | 0x400 | 0x100 | 0x10  # enabled, homed, connected, moving CW
    assert state.due(started + 1000.0) == b""
    completed = state.due(sent + 1500.0)
    assert completed[:6] == bytes.fromhex("64040e008150")
    assert struct.unpack("<HllL", completed[6:]) == (1, FIFTEEN_DEG, 0, 0x80000500)


@pytest.fixture
def fast_stage():
    stage = AptRotationStage("apt://?speed=900&angle=30")
    stage.stage()
    yield stage
    stage.unstage()


def test_stage_homes_a_stage_that_is_not_homed(fast_stage):
    status = fast_stage.status()
    assert status["homed"] and status["channel_enabled"] and status["angle_deg"] == 0.0
    assert "K10CR1 55000001" in fast_stage.describe()["stage_angle_deg"]["source"]


def test_set_returns_once_the_move_has_completed(fast_stage):
    started = time.monotonic()
    fast_stage.set({"angle_deg": 90.0})
    assert time.monotonic() - started >= 90.0 / 900  # the emulated move takes 0.1 s
    assert fast_stage.angle_deg() == 90.0
    assert not fast_stage.status()["moving_forward"]
    fast_stage.set({"view_id": 1})  # stage position 1 of a plan: 15 deg
    assert fast_stage.read()["stage_angle_deg"]["value"] == pytest.approx(15.0, abs=1e-5)


def test_the_driver_runs_on_a_serial_terminal():
    state = AptStageState(speed_deg_s=3600.0, position=FIFTEEN_DEG)
    with EmulatorPty(state) as path:
        stage = AptRotationStage(path, timeout_s=5.0)
        stage.stage()  # homes from 15 deg
        assert state.homed
        stage.set({"angle_deg": 345.0})
        assert stage.angle_deg() == pytest.approx(345.0, abs=1e-5)
        stage.unstage()
    assert state.angle_deg(time.monotonic()) == pytest.approx(345.0, abs=1e-5)


def test_a_limit_switch_stops_the_move_with_a_clear_error():
    stage = AptRotationStage("apt://?speed=3600&homed=1&cw_limit=200")
    stage.stage()
    with pytest.raises(DeviceError, match=r"move to 300 deg stopped at 200.000 deg: the CW limit"):
        stage.set({"angle_deg": 300.0})
    assert stage.status()["forward_limit_switch"]
    stage.set({"angle_deg": 100.0})  # back off the switch
    assert stage.angle_deg() == pytest.approx(100.0, abs=1e-5)
    stage.unstage()


def test_a_move_ending_without_its_status_is_checked_on_the_position_counter():
    stage = AptRotationStage("apt://?speed=3600&homed=1&short_endings=1")
    stage.stage()
    stage.set({"angle_deg": 45.0})
    assert stage.angle_deg() == pytest.approx(45.0, abs=1e-5)
    stage.unstage()


def test_a_move_that_never_ends_times_out_and_stops_the_motor():
    stage = AptRotationStage("apt://?homed=1&stall=1", timeout_s=0.2, move_timeout_s=0.2)
    stage.stage()
    with pytest.raises(DeviceTimeout, match="no MGMSG_MOT_MOVE_COMPLETED within 0.2 s"):
        stage.set({"angle_deg": 10.0})
    assert not stage.status()["moving_forward"]  # MGMSG_MOT_MOVE_STOP reached the stage
    stage.unstage()


def test_requests_are_checked_before_they_reach_the_wire(fast_stage):
    with pytest.raises(InputError, match=r"angle 361 deg is outside .* 0-360 deg"):
        fast_stage.set({"angle_deg": 361.0})
    with pytest.raises(InputError, match="angle_deg"):
        fast_stage.set({"azimuth": 10.0})
    assert fast_stage.angle_deg() == 0.0


def test_without_the_library_the_driver_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "thorlabs_apt_protocol", None)
    with pytest.raises(DriverNotInstalled, match="thorlabs-apt-protocol .*rotation-stage") as no:
        AptRotationStage("apt://").stage()
    assert no.value.remedy is Remedy.install_rotation_stage


def test_unknown_emulator_options_are_refused():
    with pytest.raises(DeviceDisconnected, match="cannot open .*unknown"):
        AptRotationStage("apt://?colour=red").stage()
