"""The dome's devices for a session, simulated or real on the wire emulators: one plan runs on
both (twin.devices.dome_devices)."""

import numpy as np
import pytest

from hwbridge.dome_plans import DomeCameraIds, DomeExposures, dome_run
from hwbridge.errors import InputError
from hwbridge.plans import chart_photographs, plan_start_times_s
from hwbridge.session import SessionSettings, run_session
from twin.components.lamps import HMILamp
from twin.devices.dome_devices import DomeDevices
from twin.devices.sim_devices import SimCamera, VirtualRig
from twin.gonio.signals import WhiteReferenceSignal
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor

EMULATED_PORTS = {
    "stage_port": "apt://?speed=36000",
    "led_port": "dmxusbpro://",
    "lctf_port": "varispec://?settle_ms=1",
}


def _cameras(plan, names):
    """Stand-in cameras (a white reference seen by an 8 x 8 CoolSNAP window)."""
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    signal = WhiteReferenceSignal(sensor, HMILamp())
    rig = VirtualRig(band_nm=550.0)
    return {
        name: SimCamera(rig, sensor, signal, plan_start_times_s(plan), name=name) for name in names
    }


def _record_sets(device, calls):
    """Note the first argument of every ``device.set`` call in ``calls``."""
    original = device.set

    def record(*args):
        calls.append(args[0])
        return original(*args)

    device.set = record


@pytest.mark.parametrize("backend", ["sim", "real"])
def test_a_dome_plan_runs_on_the_simulated_and_the_real_devices(tmp_path, backend):
    if backend == "real":
        pytest.importorskip("thorlabs_apt_protocol")  # the stage driver's extra
    exposures = DomeExposures(  # one RGB exposure, one band per LED
        rgb_hdr_s=(0.05,),
        bands_nm=(450.0, 550.0),
        band_s=(0.1, 0.1),
        schedule=((0,), (1,)),
        all_leds_s={"rgb0": 0.05, "k4": 0.1},
        reference_band_nm=550.0,
    )
    plan = dome_run(
        DomeCameraIds(("rgb0",), "k4"), exposures, stage_positions=[0, 1], leds=[0, 1, 2]
    )
    ports = EMULATED_PORTS if backend == "real" else {}
    recipe = DomeDevices.for_rig(
        load_rig("dome"),
        backend=backend,
        drive_current_ma=350.0,
        cameras=_cameras(plan, ["rgb0", "k4"]),
        **ports,
    )
    devices = recipe()
    stage, leds = devices.positioner, devices.leds
    calls = []
    _record_sets(stage, calls)
    _record_sets(leds, calls)  # light(led) switches through set(pattern)
    store = run_session(
        tmp_path / f"dome-{backend}.capture.zarr",
        plan,
        devices,
        SessionSettings(rig={}, backend=backend, seed=0, show_progress=False),
    )
    assert store.complete and store.frames("k4").shape[0] == 2 * (1 + 3)
    (angle,) = stage.read().values()
    assert angle["value"] == pytest.approx(15.0, abs=1e-5)  # position 1 of 15 deg steps
    (currents,) = leds.read().values()
    assert np.flatnonzero(currents["value"]) == [2]  # the last step lit LED 2
    assert currents["value"][2] == pytest.approx(350.0, abs=leds.current_step_ma / 2 + 1e-9)
    # Per position: one turn, the all-LED alignment frames, then each LED alone per camera.
    targets = [call for call in calls if isinstance(call, dict)]
    assert targets == [{"view_id": 0}] * 8 + [{"view_id": 1}] * 8
    lit = [np.flatnonzero(call).tolist() for call in calls if not isinstance(call, dict)]
    assert lit[:2] == [list(range(198))] * 2 and lit[2:8] == [[0], [0], [1], [1], [2], [2]]
    for device in (stage, leds, devices.tunable_filter):
        device.unstage()


def test_a_light_the_dome_does_not_have_stops_the_session(tmp_path):
    plan = chart_photographs("k4", [0.05], [198])
    devices = DomeDevices(cameras=_cameras(plan, ["k4"]))()
    with pytest.raises(InputError, match=r"LED 198 is not in 0..197"):
        run_session(
            tmp_path / "s.capture.zarr",
            plan,
            devices,
            SessionSettings(rig={}, backend="sim", seed=0, show_progress=False),
        )


def test_the_recipe_refuses_an_unknown_backend_and_missing_ports():
    config = load_rig("dome")
    recipe = DomeDevices.for_rig(config)
    assert (recipe.led_count, recipe.step_deg) == (198, 15.0)
    with pytest.raises(InputError, match=r"backend: expected one of \('sim', 'real'\)"):
        DomeDevices(backend="replay")
    with pytest.raises(InputError, match=r"serial ports \['led_port', 'lctf_port'\]"):
        DomeDevices(backend="real", stage_port="apt://")
