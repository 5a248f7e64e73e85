"""The same scene and seed give the same image bit for bit: with lamps of identical definitions
(which Mitsuba's scene optimization merged and reordered from one load to the next), through
light groups, and whatever Dr.Jit's thread count."""

import drjit as dr
import numpy as np
import pytest

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.render.light_groups import LightGroup, group_seed, render_lit
from twin.render.render import render_scene
from twin.render.scene import PinholeCamera
from twin.render.spectra import irregular_spectrum, specfilm
from twin.render.transforms import look_at, scale
from twin.render.truth import band_passbands
from twin.render.variant import activate

pytestmark = pytest.mark.render

FLAT = irregular_spectrum(SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size)))


def _alike_lamps(count: int = 4) -> dict[str, object]:
    """``count`` rectangle lamps of one definition but their place, around and above the
    origin."""
    angles = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    return {
        f"lamp_{index}": {
            "type": "rectangle",
            "to_world": look_at(
                origin=[np.cos(angle), np.sin(angle), 1.0], target=[0.0, 0.0, 0.0], up=[0, 0, 1]
            )
            @ scale(0.05),
            "emitter": {"type": "area", "radiance": FLAT},
        }
        for index, angle in enumerate(angles)
    }


def _floor() -> dict[str, object]:
    return {
        "floor": {
            "type": "rectangle",
            "to_world": scale(0.5),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.5}},
        }
    }


def _scene() -> dict[str, object]:
    activate()
    import mitsuba as mi

    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective",
            "fov": 60.0,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0.0, -0.4, 1.2], target=[0.0, 0.0, 0.0], up=[0.0, 0.0, 1.0]
            ),
            "film": specfilm(band_passbands(_bands()), 8, 8),
            "sampler": {"type": "independent", "sample_count": 4},
        },
        **_floor(),
        **_alike_lamps(),
    }


def _bands():
    from recon.spectra import WavelengthGrid

    return WavelengthGrid(np.array([450.0, 550.0, 650.0]))


def test_alike_lamps_render_the_same_image_on_every_load():
    # Before scenes were loaded without Mitsuba's optimization, 10 loads of this scene gave 5
    # different images (the merged lamps' order changed between loads).
    first = render_scene(_scene(), seed=2)
    assert first.mean() > 0
    for _ in range(5):
        np.testing.assert_array_equal(render_scene(_scene(), seed=2), first)


def test_light_groups_render_the_same_image_and_seed_each_group_apart():
    camera = PinholeCamera(np.array([0.0, -0.4, 1.2]), 0.4, 8)
    film = band_passbands(_bands())
    lamps = _alike_lamps()
    spectrum = SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size))
    groups = [
        LightGroup("left", {name: lamps[name] for name in ("lamp_0", "lamp_1")}, spectrum),
        LightGroup("right", {name: lamps[name] for name in ("lamp_2", "lamp_3")}, spectrum),
    ]
    first = render_lit(camera, film, _floor(), groups, spp=4, seed=5)
    for _ in range(3):
        np.testing.assert_array_equal(
            render_lit(camera, film, _floor(), groups, spp=4, seed=5), first
        )
    seeds = [group_seed(5, index) for index in range(4)]
    assert len(set(seeds)) == 4 and seeds == [group_seed(5, index) for index in range(4)]
    assert group_seed(6, 0) not in seeds


def test_the_image_does_not_depend_on_the_thread_count():
    activate()
    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        one = render_scene(_scene(), seed=7)
        dr.set_thread_count(3)
        three = render_scene(_scene(), seed=7)
    finally:
        dr.set_thread_count(threads)
    np.testing.assert_array_equal(one, three)
