"""Spectral textures in the node transport: a flat Lambertian patch under a distant light has
the BRDF rho / pi in every texel, whatever the light's angle (the truth divides by its cosine),
and the texture lies the way the BTF's texels do (row 0 at +y, column 0 at -x)."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid
from twin.materials import Material
from twin.materials.surfaces import SurfacePart
from twin.materials.user import flat_patch
from twin.render.shapes import part_bsdf
from twin.render.truth import truth_btf
from twin.rigs.hemisphere import direction

pytestmark = pytest.mark.render

_GRID = WavelengthGrid.regular(380.0, 780.0, 200.0)


def _patch(texture: np.ndarray) -> Material:
    spectra = SampledSpectra(_GRID, texture)
    mean = SampledSpectra(_GRID, texture.mean(axis=(0, 1)))
    return Material(
        "patch", 0.04, (SurfacePart("p", flat_patch(0.04), mean, texture=spectra),), {}, ()
    )


def test_a_textured_lambertian_patch_reads_rho_over_pi_in_every_texel():
    # Spectrally flat texels, so that the bands' averaging leaves each value as it is.
    levels = np.random.default_rng(0).uniform(0.05, 0.9, (8, 8, 1))
    material = _patch(np.repeat(levels, _GRID.size, axis=2))
    lights = direction(np.array([0.0, 60.0]), np.array([0.0, 30.0]))
    views = direction(np.array([0.0, 0.0]), np.array([0.0, 0.0]))
    btf = truth_btf(material, lights, views, texels=8, spp=4)
    for pair in btf:
        np.testing.assert_allclose(pair, np.broadcast_to(levels / np.pi, pair.shape), rtol=2e-6)


def test_texture_rows_run_down_from_plus_y_and_columns_right_from_minus_x():
    texture = np.full((2, 4, _GRID.size), 0.1)
    texture[0, 0] = 0.9  # the top-left texel: -x, +y
    btf = truth_btf(_patch(texture), np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]), texels=4)
    bright = np.argwhere(btf[0, ..., 0] > 0.5 / np.pi)
    np.testing.assert_array_equal(bright, [[0, 0], [1, 0]])  # 2 x 4 texture over 4 x 4 texels


def test_a_textured_part_has_no_mitsuba_bsdf_of_its_own():
    material = _patch(np.full((2, 2, _GRID.size), 0.5))
    assert part_bsdf(material.parts[0], unit=True)["type"] == "diffuse"
    with pytest.raises(InputError, match="node transport"):
        part_bsdf(material.parts[0])
