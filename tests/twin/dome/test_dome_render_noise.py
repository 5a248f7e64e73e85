"""The dome's render noise against its sensors' temporal noise (twin.dome.render): a rendered
frame's noise must be a small addition to the noise the cameras add themselves."""

import numpy as np
import pytest

from hwbridge.dome_layout import SPECTRAL_CAMERA
from twin.dome.holder import holder_scene_parts
from twin.dome.render import (
    DOME_SPP,
    DomeView,
    dome_camera,
    dome_scene_rates,
)
from twin.dome.signals import DomeScene, RenderedDomeSignal
from twin.materials import Material
from twin.materials.sample_holder import holder_parts
from twin.render.node_transport import NodeScene
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render


@pytest.mark.parametrize("camera", [0, 6, SPECTRAL_CAMERA])
def test_a_white_fields_render_noise_is_far_below_the_sensors_temporal_noise(camera):
    """The white standard on the holder under one LED, rendered at the default spp with two
    seeds, in the central 32 px of the 320 px field (20 mm, inside the 41 mm opening): per RGB
    channel and per band of the tunable filter, the render noise (the two renders' difference
    over sqrt 2) scaled to the brightest unclipped frame (the white at the sensor's saturation
    capacity, where the render's share of the noise is largest: it grows as the signal, shot
    noise as its root) is below a fifth of the temporal noise there (shot and read noise), so
    it adds under 2 % to a frame's noise. Measured at 16 spp: 0.13 (the top camera), 0.09 (arc
    camera 6), 0.08 (the spectral camera), the same in every channel (the noise is the bounce
    off the holder's walls, whatever the wavelength); at 4 spp 0.18, 0.25 and 0.19. Mitsuba's
    spectral path tracer at 64 spp scattered a band by 0.7 % per pixel: 1.0 to 1.3 here."""
    config = load_rig("dome")
    scene = NodeScene(holder_scene_parts("white", None))
    view = DomeView(config, camera, 320, window=32)
    first, second = (
        dome_scene_rates(config, scene, view, stage_deg=15.0, leds=[60], spp=DOME_SPP, seed=seed)
        .reshape(-1, view.weights.shape[1])
        .astype(np.float64)
        for seed in (1, 2)
    )
    mean = (first + second).mean(axis=0) / 2
    assert np.all(np.abs(first / mean - 1) < 0.05)  # all of the window sees the white field
    ratio = _render_over_temporal_noise(config, camera, first, second)
    assert ratio.size == (33 if camera == SPECTRAL_CAMERA else 3)
    assert ratio.max() < 0.2, ratio


def _render_over_temporal_noise(config, camera, first, second) -> np.ndarray:
    """Per channel, the render noise of two renders ``(n_pixels, n_channels)`` of a white field
    (their difference over sqrt 2, relative to the mean) at the sensor's saturation capacity
    over the temporal noise there (shot and read noise)."""
    relative_noise = (first - second).std(axis=0) / np.sqrt(2) / ((first + second).mean(0) / 2)
    _, sensor, _ = dome_camera(config, camera, 320)
    full = sensor.saturation_capacity_e
    read_e = sensor.config.read_noise_dn / sensor.config.system_gain_dn_per_e
    return relative_noise * full / np.sqrt(full + read_e**2)


@pytest.mark.parametrize("camera", [0, SPECTRAL_CAMERA])
def test_an_led_of_a_pass_renders_as_its_own_render_with_the_same_noise(camera):
    """LED 60 in a pass of LEDs 58-62 (dome_scene_rates with each, the captures' default) equals its
    one-LED render with the pass's seed to float rounding, so its render noise is the one-LED
    renders' (the test above): against the one-LED render with another seed it differs by the
    noise bound held there, a fifth of the temporal noise at saturation."""
    config = load_rig("dome")
    scene = NodeScene(holder_scene_parts("white", None))
    view = DomeView(config, camera, 320, window=32)
    leds = [58, 59, 60, 61, 62]
    passed = dome_scene_rates(
        config, scene, view, stage_deg=15.0, leds=leds, spp=DOME_SPP, seed=1, each=True
    )[2]
    alone, other = (
        dome_scene_rates(config, scene, view, stage_deg=15.0, leds=[60], spp=DOME_SPP, seed=seed)
        for seed in (1, 2)
    )
    np.testing.assert_allclose(passed, alone, rtol=1e-5)
    channels = view.weights.shape[1]
    first, second = (rates.reshape(-1, channels).astype(np.float64) for rates in (passed, other))
    assert _render_over_temporal_noise(config, camera, first, second).max() < 0.2


def test_all_leds_of_one_pass_are_its_images_summed_within_the_render_noise():
    """A run's alignment frame (the sample with every LED of the stage position lit) is, where
    those LEDs fit in one pass of every channel, the sum of the pass's images (no render of its
    own): to float rounding the sum of the LEDs' frames, and against a render of the LEDs
    together (another seed) it differs by less than the noise bound held above. The spectral
    camera, whose pass holds each LED's scheduled bands only, renders the LEDs together."""
    config = load_rig("dome")
    leds = (58, 59, 60, 61, 62)
    standard = holder_scene_parts("white", None)[len(holder_parts()) :]
    sample = Material("white standard", 0.05, tuple(standard), {}, ())  # as a run's sample
    scene = DomeScene(
        config, sample, ("material",), 700.0, 320, 32, DOME_SPP, (550.0, 600.0), "pose", leds,
        {led: (0,) for led in leds},
    )  # fmt: skip
    signal = RenderedDomeSignal(scene, 0)
    together = signal.rates("material", 15.0, leds)
    each = sum(signal.rates("material", 15.0, (led,)).astype(np.float64) for led in leds)
    np.testing.assert_allclose(together, each, rtol=1e-5)  # a render would differ by its noise
    rendered = dome_scene_rates(
        config, scene.node_scene("material"), signal.view, stage_deg=15.0, leds=leds, seed=3
    )
    first, second = (rates.reshape(-1, 3).astype(np.float64) for rates in (together, rendered))
    assert _render_over_temporal_noise(config, 0, first, second).max() < 0.2
    spectral = RenderedDomeSignal(scene, SPECTRAL_CAMERA).rates("material", 15.0, leds)
    assert np.all(spectral[..., 1] > 0)  # a band no LED's pass holds: rendered
