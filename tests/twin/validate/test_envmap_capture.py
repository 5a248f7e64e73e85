"""Mirror-sphere capture of a spectral environment map (thesis 4.2) recovers a known map."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.scene import PinholeCamera
from twin.rigs.hemisphere import angle_between_deg, direction
from twin.validate.envmap_capture import capture_mirror_sphere, unwrap_mirror_sphere

pytestmark = pytest.mark.render


def test_mirror_sphere_capture_recovers_a_known_spectral_map():
    height, width = 16, 32
    theta = (np.arange(height) + 0.5) * 180 / height
    phi = (np.arange(width) + 0.5) * 360 / width
    directions = direction(theta[:, None], phi[None, :])
    spectrum = np.linspace(0.5, 1.5, DEFAULT_GRID.size)
    truth = (1.0 + 0.8 * directions[..., 2:] + 0.4 * directions[..., :1]) * spectrum
    captured, image = capture_mirror_sphere(
        {"environment": spectral_envmap(SpectralMap(truth, DEFAULT_GRID))},
        DEFAULT_GRID,
        pixels=128,
        spp=256,
        height=height,
        width=width,
    )
    assert image.shape == (128, 128, DEFAULT_GRID.size)
    to_camera = np.array([0.0, -1.0, 0.3]) / np.linalg.norm([0.0, -1.0, 0.3])
    # Away from the blind spot behind the sphere and from the polar rows (all azimuths of a pole
    # row meet in a few image pixels), the map comes back to within Monte Carlo noise.
    seen = angle_between_deg(directions, -to_camera) > 40
    seen[[0, -1]] = False
    error = np.abs(captured.radiance - truth)[seen] / truth[seen]
    assert np.median(error) < 0.005 and np.percentile(error, 95) < 0.03


def test_unwrap_refuses_a_blind_spot_hiding_everything():
    camera = PinholeCamera(np.array([0.0, -30.0, 0.0]), 0.11, 16)
    with pytest.raises(InputError, match="blind_spot_deg"):
        unwrap_mirror_sphere(
            np.ones((16, 16, DEFAULT_GRID.size)), camera, 0.05, DEFAULT_GRID, blind_spot_deg=181
        )
