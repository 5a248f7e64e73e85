"""The spectral environment map emitter against analytic irradiance (thesis 4.2, Figure 4.6)."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.render.plugins.registry import register_once
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.render import render_scene
from twin.render.spectra import irregular_spectrum, specfilm
from twin.render.truth import band_passbands
from twin.render.variant import activate

pytestmark = pytest.mark.render
ALBEDO = 0.5
CENTRES_NM = np.array([450.0, 550.0, 650.0])


def _plane_under(spectral_map: SpectralMap, *, importance: bool, spp: int) -> np.ndarray:
    """A diffuse square of albedo 0.5 facing +z under the map, seen from above: (32, 32, 3)."""
    activate()
    import mitsuba as mi

    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective",
            "fov": 20,
            "to_world": mi.ScalarTransform4f.look_at(
                origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]
            ),
            "film": specfilm(band_passbands(WavelengthGrid(CENTRES_NM)), 32, 32),
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "environment": spectral_envmap(spectral_map, importance=importance),
        "plane": {
            "type": "rectangle",
            "bsdf": {
                "type": "diffuse",
                "reflectance": irregular_spectrum(
                    SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, ALBEDO))
                ),
            },
        },
    }
    return render_scene(scene, seed=1)


def _cosine_integrals(height: int, width: int) -> np.ndarray:
    """Exact integral of cos(theta) d omega over every pixel of the upper hemisphere."""
    edges = np.linspace(0.0, np.pi, height + 1)
    per_row = np.pi / width * (np.sin(edges[1:]) ** 2 - np.sin(edges[:-1]) ** 2)
    per_row[edges[:-1] >= np.pi / 2] = 0.0
    return np.repeat(per_row[:, None], width, axis=1)


def test_constant_map_gives_the_analytic_irradiance_within_1_percent():
    radiance = np.linspace(1.0, 2.0, DEFAULT_GRID.size)
    image = _plane_under(
        SpectralMap(np.tile(radiance, (16, 32, 1)), DEFAULT_GRID), importance=True, spp=64
    )
    # E = pi L over the upper hemisphere, L_o = albedo E / pi: the map's radiance times the albedo
    # (band passbands of unit area, radiance linear in wavelength).
    expected = ALBEDO * np.interp(CENTRES_NM, DEFAULT_GRID.wavelengths_nm, radiance)
    np.testing.assert_allclose(image.mean(axis=(0, 1)), expected, rtol=0.01)


def test_importance_sampling_lowers_the_variance_for_a_sun_like_map():
    height, width = 32, 64
    radiance = np.full((height, width, DEFAULT_GRID.size), 0.05)
    radiance[3:5, 10:12] = 200.0  # a small, bright sun 15-25 degrees from the zenith
    sun = SpectralMap(radiance, DEFAULT_GRID)
    irradiance = (radiance[..., 0] * _cosine_integrals(height, width)).sum()
    expected = ALBEDO * irradiance / np.pi
    sampled = _plane_under(sun, importance=True, spp=16)
    uniform = _plane_under(sun, importance=False, spp=16)
    np.testing.assert_allclose(sampled.mean(axis=(0, 1)), expected, rtol=0.01)
    spread_sampled = sampled.std(axis=(0, 1)) / sampled.mean(axis=(0, 1))
    spread_uniform = uniform.std(axis=(0, 1)) / uniform.mean(axis=(0, 1))
    assert np.all(spread_sampled < 0.25) and np.all(spread_uniform > 5 * spread_sampled)


def test_solid_angles_cover_the_sphere_and_bad_maps_are_refused():
    spectral_map = SpectralMap(np.ones((7, 9, DEFAULT_GRID.size)), DEFAULT_GRID)
    assert spectral_map.solid_angles().sum() == pytest.approx(4 * np.pi)
    with pytest.raises(InputError, match="lat-long map"):
        SpectralMap(np.ones((4, 8, 5)), DEFAULT_GRID)
    with pytest.raises(InputError, match="non-negative"):
        SpectralMap(-np.ones((4, 8, DEFAULT_GRID.size)), DEFAULT_GRID)
    irregular = WavelengthGrid(np.array([400.0, 410.0, 430.0]))
    with pytest.raises(InputError, match="regular wavelength grid"):
        SpectralMap(np.ones((4, 8, 3)), irregular)


def test_plugins_are_registered_at_import_and_only_once():
    registered = []

    def register(name, plugin):
        registered.append(name)

    assert not register_once("spectral_envmap", register, lambda props: None)
    assert register_once("test_only_plugin", register, lambda props: None)
    assert not register_once("test_only_plugin", register, lambda props: None)
    assert registered == ["test_only_plugin"]
