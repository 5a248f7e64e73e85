"""render_scene: a scene dict or loaded scene to a float64 image, the same for the same seed."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.render.render import render_scene
from twin.render.spectra import irregular_spectrum, specfilm
from twin.render.truth import band_passbands
from twin.render.variant import activate

pytestmark = pytest.mark.render
BANDS = WavelengthGrid(np.array([450.0, 550.0, 650.0]))


def _scene(spp: int = 4) -> dict[str, object]:
    """A grey square under a directional light, seen by a 12 x 8 px, 3-band film."""
    activate()
    import mitsuba as mi

    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {
            "type": "orthographic",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0.0, 0.0, 1.0], target=[0.0, 0.0, 0.0], up=[0.0, 1.0, 0.0]
            ),
            "film": specfilm(band_passbands(BANDS), 12, 8),
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "light": {
            "type": "directional",
            "direction": [0.3, 0.0, -1.0],
            "irradiance": irregular_spectrum(SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size))),
        },
        "square": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().scale([2.0, 2.0, 1.0]),
            "bsdf": {
                "type": "diffuse",
                "reflectance": irregular_spectrum(
                    SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.5))
                ),
            },
        },
    }


def test_render_scene_gives_the_films_float64_image_the_same_for_the_same_seed():
    import mitsuba as mi

    image = render_scene(_scene(), seed=3)
    assert image.dtype == np.float64 and image.shape == (8, 12, 3)
    assert np.all(np.isfinite(image)) and image.mean() > 0
    np.testing.assert_array_equal(render_scene(_scene(), seed=3), image)
    np.testing.assert_array_equal(render_scene(mi.load_dict(_scene()), seed=3), image)
    assert not np.array_equal(render_scene(_scene(), seed=4), image)


def test_render_scene_matches_mitsubas_render_and_takes_the_sample_count():
    import mitsuba as mi

    scene = mi.load_dict(_scene())
    np.testing.assert_array_equal(
        render_scene(scene, seed=5), np.array(mi.render(scene, seed=5), np.float64)
    )
    np.testing.assert_array_equal(
        render_scene(scene, seed=5, spp=16), render_scene(_scene(spp=16), seed=5)
    )
    with pytest.raises(InputError, match="spp"):
        render_scene(scene, spp=0)
