"""A lab's devices in a session (twin.devices.lab_devices): the real stage, LEDs and LCTF on their
wire emulators, the twin's cameras rendering the state read back from them."""

import numpy as np
import pytest

from hwbridge.dome_plans import DomeCameraIds, DomeExposures, dome_run
from hwbridge.errors import InputError
from hwbridge.lab import load_lab
from hwbridge.plans import chart_photographs, gonio_sample_run, plan_start_times_s
from hwbridge.session import SessionSettings, run_session
from twin.devices.lab_devices import LabDevices, ReadBackLeds, ReadBackStage
from twin.devices.sim_devices import SimDomeDevices, SimGonioDevices, VirtualRig
from twin.sensor.model import Sensor

pytest.importorskip("thorlabs_apt_protocol")  # the stage driver's extra

EMULATED_LAB = """\
rig: dome
devices:
  stage: apt://?speed=36000
  leds: dmxusbpro://
  lctf: varispec://?settle_ms=1
  spectral_camera: sim
  rgb_cameras: sim
"""


def state_signal(rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
    """Electrons that tell the rig's state apart: the stage angle, the LEDs on and their
    current, the band (a test signal, so that a frame shows what the devices were told)."""
    lit = 0.0 if rig.led_pattern is None else float(np.flatnonzero(rig.led_pattern).sum() + 1)
    band = 0.0 if rig.band_nm is None else rig.band_nm
    level = 100 + rig.stage_deg + 7 * lit + rig.led_current_ma / 10 + band / 100
    return np.full((8, 8), 50 * level * exposure_s, np.float32)


def _plan():
    exposures = DomeExposures(  # one RGB exposure, one band per LED
        rgb_hdr_s=(0.05,),
        bands_nm=(450.0, 550.0),
        band_s=(0.1, 0.1),
        schedule=((0,), (1,)),
        all_leds_s={"rgb00": 0.05, "spectral": 0.1},
        reference_band_nm=550.0,
    )
    cameras = DomeCameraIds(("rgb00",), "spectral")
    return dome_run(cameras, exposures, stage_positions=[0, 1], leds=[0, 1, 2])


def _recipe(plan):
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    cameras = tuple((name, sensor, state_signal) for name in ("rgb00", "spectral"))
    return SimDomeDevices(cameras, plan_start_times_s(plan), 15.0, 198)


def test_the_emulated_lab_gives_the_frames_of_the_simulated_devices(tmp_path):
    """Each frame shows the stage angle, the LEDs and the band: the twin's cameras render the
    state read back from the stage's counter, the acknowledged DMX universe and the LCTF as the
    simulated devices set it, bit for bit."""
    plan = _plan()
    (tmp_path / "lab.yaml").write_text(EMULATED_LAB)
    lab = LabDevices(load_lab(tmp_path / "lab.yaml"), _recipe(plan))
    assert lab.backend == "real"
    stores = {}
    for name, recipe in (("sim", _recipe(plan)), ("lab", lab)):
        devices = recipe(0, None)
        settings = SessionSettings(rig={}, backend=recipe.backend, seed=0, show_progress=False)
        stores[name] = run_session(tmp_path / f"{name}.capture.zarr", plan, devices, settings)
        if name == "lab":
            assert isinstance(devices.positioner, ReadBackStage)
            assert isinstance(devices.leds, ReadBackLeds)
            (angle,) = devices.positioner.read().values()
            assert angle["value"] == pytest.approx(15.0, abs=1e-5)  # position 1, from the counter
            (currents,) = devices.leds.read().values()
            assert np.flatnonzero(currents["value"]).tolist() == [2]  # the last step's LED
            devices.unstage()
    for camera in ("rgb00", "spectral"):
        simulated, wired = stores["sim"].frames(camera)[:], stores["lab"].frames(camera)[:]
        assert len(np.unique(simulated)) > 4  # the frames do tell the states apart
        np.testing.assert_array_equal(wired, simulated)
    assert stores["lab"].metadata.backend == "real"


def test_a_light_the_dome_does_not_have_stops_the_session(tmp_path):
    plan = chart_photographs("spectral", [0.05], [198])
    (tmp_path / "lab.yaml").write_text(EMULATED_LAB)
    devices = LabDevices(load_lab(tmp_path / "lab.yaml"), _recipe(plan))(0, None)
    with pytest.raises(InputError, match=r"LED 198 is not in 0..197"):
        run_session(
            tmp_path / "s.capture.zarr",
            plan,
            devices,
            SessionSettings(rig={}, backend="real", seed=0, show_progress=False),
        )
    devices.unstage()


def test_a_devices_file_with_no_real_device_is_the_simulated_backend(tmp_path):
    (tmp_path / "lab.yaml").write_text(
        "rig: dome\ndevices: {stage: sim, leds: sim, lctf: sim, spectral_camera: sim, "
        "rgb_cameras: sim}\n"
    )
    plan = _plan()
    assert LabDevices(load_lab(tmp_path / "lab.yaml"), _recipe(plan)).backend == "sim"


def test_the_gonioreflectometer_s_lctf_on_the_wire_gives_the_simulated_frames(tmp_path):
    """The gonioreflectometer's one driven role: its camera renders the band the VariSpec
    reports."""
    plan = gonio_sample_run("k4", [0, 1], [450.0, 550.0, 650.0], [0.1, 0.1, 0.1])
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    recipe = SimGonioDevices("k4", sensor, state_signal, plan_start_times_s(plan), views=2)
    (tmp_path / "lab.yaml").write_text(
        "rig: gonioreflectometer\ndevices: {camera: sim, lctf: 'varispec://?settle_ms=1', "
        "monitor: sim, positioner: sim, lamp: sim}\n"
    )
    stores = {}
    for name, devices in (
        ("sim", recipe),
        ("lab", LabDevices(load_lab(tmp_path / "lab.yaml"), recipe)),
    ):
        built = devices(0, None)
        settings = SessionSettings(rig={}, backend=devices.backend, seed=0, show_progress=False)
        stores[name] = run_session(tmp_path / f"{name}.capture.zarr", plan, built, settings)
        assert built.tunable_filter is not None
        (band,) = built.tunable_filter.read().values()
        assert band["value"] == 650.0  # the last step's band, asked of the controller
        built.unstage()
    np.testing.assert_array_equal(stores["lab"].frames("k4")[:], stores["sim"].frames("k4")[:])
