"""Simulated devices and their signals (twin.devices.sim_devices, twin.gonio.signals)."""

import numpy as np
import pytest

from hwbridge.errors import InputError
from hwbridge.protocols import Camera, Positioner, Shutter, TunableFilter
from twin.components.lamps import HMILamp, QTHLamp
from twin.devices.sim_devices import SimCamera, SimPositioner, SimTunableFilter, VirtualRig
from twin.gonio.signals import WhiteReferenceSignal
from twin.gonio.sim_session import run_demo_session
from twin.sensor.model import Sensor


def test_white_reference_signal_carries_the_hmi_flicker():
    sensor = Sensor("coolsnap_k4", roi=(4, 4))
    rig = VirtualRig(band_nm=550.0)
    hmi, qth = WhiteReferenceSignal(sensor, HMILamp()), WhiteReferenceSignal(sensor, QTHLamp())
    starts = np.linspace(0, 0.2, 9)
    short = [hmi(rig, t, 0.05)[0, 0] for t in starts]
    full_period = [hmi(rig, t, 1 / 15)[0, 0] for t in starts]
    steady = [qth(rig, t, 0.05)[0, 0] for t in starts]
    assert np.ptp(short) / np.mean(short) > 0.01
    assert np.ptp(full_period) / np.mean(full_period) < 1e-6
    assert np.ptp(steady) == 0


def test_simulated_devices_follow_the_protocols_and_share_state():
    rig = VirtualRig(seed=1, steps=[2, 0])
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    camera = SimCamera(rig, sensor, WhiteReferenceSignal(sensor, HMILamp()), np.zeros(3), name="k4")
    lctf, positioner = SimTunableFilter(rig), SimPositioner(rig, 2)
    assert (
        isinstance(camera, Camera)
        and isinstance(camera, Shutter)
        and isinstance(lctf, TunableFilter)
        and isinstance(positioner, Positioner)
    )
    lctf.set(550.0)
    positioner.set({"view_id": 1})
    assert rig.band_nm == 550.0 and rig.view_id == 1
    camera.set_exposure(0.1)
    assert rig.step == 2
    bright, _ = camera.snap()
    assert rig.step == 0  # each frame moves the rig on to its next step
    camera.set_shutter(False)
    dark, _ = camera.snap()
    assert bright.mean() > dark.mean() + 100
    with pytest.raises(InputError, match="built for 2 steps"):
        camera.snap()
    with pytest.raises(InputError, match="view_id"):
        positioner.set({"view_id": 5})


def test_a_simulated_frame_follows_from_the_seed_and_the_step_the_rig_takes():
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    signal = WhiteReferenceSignal(sensor, HMILamp())

    def frames(seed, steps):
        camera = SimCamera(
            VirtualRig(band_nm=550.0, seed=seed, steps=steps), sensor, signal, [0.0] * 3
        )
        camera.set_exposure(0.1)
        return [camera.snap()[0] for _ in steps]

    first, second, third = frames(1, [0, 1, 2])
    np.testing.assert_array_equal(frames(1, [2, 1])[0], third)  # a resumed session's frame
    assert not np.array_equal(first, second)
    assert not np.array_equal(frames(2, [0])[0], first)


@pytest.mark.render
def test_rendered_session_renders_each_view_once_and_completes(tmp_path, monkeypatch):
    from twin.gonio.render import GonioScene

    rendered_poses, scenes = [], []
    render, build = GonioScene.part_rates, GonioScene.__init__

    def counting_render(scene, pose, *args, **kwargs):
        rendered_poses.append(pose)
        return render(scene, pose, *args, **kwargs)

    def counting_build(scene, *args, **kwargs):
        scenes.append(scene)
        build(scene, *args, **kwargs)

    monkeypatch.setattr(GonioScene, "part_rates", counting_render)
    monkeypatch.setattr(GonioScene, "__init__", counting_build)
    store = run_demo_session(tmp_path / "rendered.capture.zarr", 1, rendered=True)
    assert store.complete
    # Two direction pairs, every band of a view from one render of one scene: two renders.
    assert len(rendered_poses) == 2 and len(scenes) == 1
    assert rendered_poses[0] != rendered_poses[1]
    frames, index = store.frames("k4")[:], store.index("k4")
    at_550 = np.flatnonzero(index["band_nm"] == 550.0)
    assert len(at_550) == 2
    # The two direction pairs see the chart differently.
    assert not np.array_equal(frames[at_550[0]], frames[at_550[1]])


def test_lamp_leds_and_monitor_follow_the_protocols(tmp_path):
    from hwbridge.protocols import Lamp, LedArray, Spectrometer
    from recon.spectra import DEFAULT_GRID
    from twin.devices.sim_devices import SimLamp, SimLedArray, SimSpectrometer

    rig = VirtualRig()
    lamp, leds = SimLamp(rig), SimLedArray(rig, 198)
    monitor = SimSpectrometer(rig, HMILamp(), DEFAULT_GRID)
    assert (
        isinstance(lamp, Lamp) and isinstance(leds, LedArray) and isinstance(monitor, Spectrometer)
    )
    leds.set(np.arange(198) == 7)
    assert rig.led_pattern.sum() == 1
    with pytest.raises(InputError, match="198"):
        leds.set(np.ones(5))
    rig.clock_s = 0.0
    monitor.trigger()
    early = monitor.read()["monitor_counts"]["value"]
    rig.clock_s = 5 * 3600.0
    monitor.trigger()
    late = monitor.read()["monitor_counts"]["value"]
    assert np.all(late < early)  # the HMI lamp's slow drift (thesis Fig. 3.5c)
    lamp.set(False)
    monitor.trigger()
    assert monitor.read()["monitor_counts"]["value"].max() == 0


def test_sessions_record_the_lamp_monitor_with_lit_frames(tmp_path):
    store = run_demo_session(tmp_path / "monitored.capture.zarr", 2)
    index = store.index("k4")
    lit = index["kind"] == "sample"
    assert np.all(np.isfinite(index["lamp_monitor"][lit])) and np.all(
        np.isnan(index["lamp_monitor"][~lit])
    )


def test_sessions_switch_the_step_led_on_alone(tmp_path):
    from hwbridge.plans import chart_photographs, plan_start_times_s
    from hwbridge.session import SessionDevices, SessionSettings, run_session
    from twin.devices.sim_devices import SimLedArray

    plan = chart_photographs("k4", [0.05], [3, 7, -2])
    rig = VirtualRig(band_nm=550.0)
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    patterns = []
    leds = SimLedArray(rig, 198)
    original_set = leds.set

    def record(pattern, current_ma=None):
        original_set(pattern, current_ma)
        patterns.append(np.flatnonzero(rig.led_pattern).tolist())

    leds.set = record
    camera = SimCamera(
        rig, sensor, WhiteReferenceSignal(sensor, HMILamp()), plan_start_times_s(plan), name="k4"
    )
    store = run_session(
        tmp_path / "leds.capture.zarr",
        plan,
        SessionDevices(cameras={"k4": camera}, leds=leds),
        SessionSettings(rig={}, backend="sim", seed=0, show_progress=False),
    )
    assert store.complete
    assert patterns[0] == [3] and patterns[1] == [7] and len(patterns[2]) == 198
