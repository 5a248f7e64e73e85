"""User materials from files (twin.materials.user): the example recipes load, the painted card's
spectralized texture matches the spectra it was painted with, and bad recipes fail with one line
that names the field."""

from pathlib import Path

import numpy as np
import pytest

from recon.errors import InputError
from recon.metrics import delta_e94, relative_error
from recon.rgb_upsampling import read_srgb_image, srgb_response
from twin.materials import load_material
from twin.materials.builders import chart_colour
from twin.materials.user import PATCH_HEIGHT_M
from twin.materials.user_examples import example_card_truth, write_user_examples


@pytest.fixture(scope="module")
def examples(tmp_path_factory) -> list[Path]:
    return write_user_examples(tmp_path_factory.mktemp("examples"))


def test_examples_load_as_materials_with_their_textures(examples):
    tile, card = (load_material(path) for path in examples)
    (tile_part,) = tile.parts
    assert tile_part.texels == (32, 32) and tile_part.roughness == 0.3
    # The OBJ is in millimetres; mesh_scale 0.001 puts it into the 40 mm square.
    low, high = tile_part.mesh.bounds
    np.testing.assert_allclose(low[:2], [-0.02, -0.02])
    assert 0 < low[2] < high[2] < 0.001
    (card_part,) = card.parts
    assert card_part.texels == (64, 64) and card_part.roughness is None
    np.testing.assert_allclose(card_part.mesh.vertices[:, 2], PATCH_HEIGHT_M)
    # The part's reflectance of record is its texture's mean.
    texture = card_part.texture
    mean = np.interp(550, texture.wavelengths_nm, texture.values.mean(axis=(0, 1)))
    assert np.interp(550, card_part.reflectance.wavelengths_nm, card_part.reflectance.values) == (
        pytest.approx(mean, rel=1e-6)
    )


def test_spectralized_card_matches_the_paint_spectra_it_was_photographed_from(examples):
    """Three chips' spectra at one pixel each spread over the 8-bit sRGB photograph: measured
    0.21 % (Eq. 6.8) and Delta E94 0.10 on average over the texels."""
    card = load_material(examples[1])
    truth, _ = example_card_truth()
    estimate = card.parts[0].texture.values
    assert relative_error(estimate, truth.values).mean() < 1.0
    colour_error = delta_e94(estimate.reshape(-1, 33), truth.values.reshape(-1, 33), truth.grid)
    assert colour_error.mean() < 0.5


_TILE = """\
name: t
material: user
size_m: 0.04
parts:
"""


def _write(folder: Path, parts: str) -> Path:
    path = folder / "m.yaml"
    path.write_text(_TILE + parts)
    return path


def _refused(path: Path) -> str:
    with pytest.raises(InputError) as error:
        load_material(path)
    message = str(error.value)
    assert "\n" not in message and str(path) in message
    return message


def test_a_colour_dataset_spectrum_is_the_charts_own(tmp_path):
    path = _write(
        tmp_path,
        "  - name: a\n    spectrum: {colour: ColorChecker N Ohta/dark skin}\n"
        "  - name: b\n    spectrum: {chart: dark skin}\n",
    )
    material = load_material(path)
    np.testing.assert_allclose(material.spectra["a"].values, chart_colour("dark skin").values)
    np.testing.assert_allclose(material.spectra["b"].values, chart_colour("dark skin").values)


@pytest.mark.parametrize(
    ("parts", "named"),
    [
        ("  - name: a\n    texture: missing.exr\n", "parts.a.texture: no file"),
        (
            "  - name: a\n    texture: x.exr\n    spectrum: {chart: dark skin}\n",
            "exactly one of spectrum, texture, rgb_texture",
        ),
        (
            "  - name: a\n    spectrum: {chart: dark skin}\n"
            "    bsdf: {type: rough_conductor, roughness: 0.1, metal: Ag}\n",
            "rough_conductor's colour is its metal's",
        ),
        (
            "  - name: a\n    spectrum: {chart: dark skin}\n"
            "    bsdf: {type: rough_dielectric, roughness: 0.1}\n",
            "a rough_dielectric is clear; give no reflectance",
        ),
        (
            "  - name: a\n    spectrum: {chart: dark skin}\n"
            "    bsdf: {type: rough_plastic, roughness: 0.1, ior: 1.3}\n",
            "ior: given only for type rough_dielectric",
        ),
        (
            "  - name: a\n    bsdf: {type: rough_dielectric, roughness: 0.1, ior: 0.8}\n",
            "parts.0.bsdf.ior",
        ),
        (
            "  - name: a\n    bsdf: {type: rough_conductor, roughness: 0.1, metal: Xx}\n",
            "metal: 'Xx' is not one of Mitsuba's presets",
        ),
        (
            "  - name: a\n    spectrum: {colour: No Such Chart/dark skin}\n",
            "parts.a.spectrum.colour: no spectrum",
        ),
        ("  - name: a\n    spectrum: {csv: two.csv}\n", "name one with column"),
        ("  - name: a\n    spectrum: {csv: short.csv}\n", "covers 450-700 nm"),
        ("  - name: a\n    mesh: big.obj\n    spectrum: {chart: dark skin}\n", "big.obj"),
        ("  - name: a\n    mesh: small.obj\n    texture: x.exr\n", "needs a mesh with texture"),
        (
            "  - name: a\n    spectrum: {chart: dark skin}\n"
            "  - name: a\n    spectrum: {chart: dark skin}\n",
            "used more than once",
        ),
    ],
)
def test_bad_recipes_fail_naming_the_field(tmp_path, examples, parts, named):
    tile_folder = examples[0].parent
    (tmp_path / "x.exr").write_bytes((tile_folder / "tile_reflectance.exr").read_bytes())
    (tmp_path / "two.csv").write_text("wavelength_nm,a,b\n400,0.1,0.2\n720,0.1,0.2\n")
    (tmp_path / "short.csv").write_text("wavelength_nm,a\n450,0.1\n700,0.1\n")
    # A mesh in millimetres without mesh_scale is 1000 times too large, and has no uv.
    (tmp_path / "big.obj").write_text("v -20 -20 0\nv 20 -20 0\nv 20 20 0\nf 1 2 3\n")
    (tmp_path / "small.obj").write_text("v -0.01 -0.01 0\nv 0.01 -0.01 0\nv 0 0.01 0\nf 1 2 3\n")
    assert named in _refused(_write(tmp_path, parts))


def test_a_clear_dielectric_part_takes_its_index(tmp_path):
    path = _write(
        tmp_path,
        "  - name: glass\n    bsdf: {type: rough_dielectric, roughness: 0.1, ior: 1.7}\n"
        "  - name: film\n    bsdf: {type: rough_dielectric, roughness: 0.2}\n",
    )
    glass, film = load_material(path).parts
    assert (glass.dielectric_ior, glass.roughness, glass.bsdf_kind) == (
        1.7,
        0.1,
        "rough dielectric",
    )
    assert film.dielectric_ior == 1.5 and film.conductor is None


def test_a_mesh_out_of_the_sample_square_says_what_was_expected(tmp_path):
    path = _write(tmp_path, "  - name: a\n    mesh: big.obj\n    spectrum: {chart: dark skin}\n")
    (tmp_path / "big.obj").write_text("v -20 -20 0\nv 20 -20 0\nv 20 20 0\nf 1 2 3\n")
    message = _refused(path)
    assert "big.obj spans x, y to 20000.0 mm" in message and "mesh_scale" in message


def test_an_rgb_texture_upsampled_by_jakob2019_has_the_images_colours(tmp_path, examples):
    card = examples[1].parent / "card.png"
    path = _write(
        tmp_path,
        f"  - name: a\n    rgb_texture: {{image: {card}, method: jakob2019}}\n",
    )
    texture = load_material(path).parts[0].texture
    linear = read_srgb_image(card)
    np.testing.assert_allclose(texture.values @ srgb_response(), linear, atol=0.02)
    refused = _write(
        tmp_path,
        f"  - name: a\n    rgb_texture: {{image: {card}, method: jakob2019, "
        "known_spectra: s.csv}\n",
    )
    assert "takes no known_spectra" in _refused(refused)


def test_the_texture_truth_of_a_textured_part_fits_its_texels_spectra(examples):
    """texture_truth (the dome study's analytic truth) fits every texel with the material's
    basis; a spectral texture enters it with its own spectra (the tile's eight), so the fit
    reproduces the rendered truth, which the texture's mean spectrum alone cannot."""
    from twin.render.truth import texture_truth, truth_btf
    from twin.rigs.hemisphere import direction

    tile = load_material(examples[0])
    light = direction(np.array([30.0]), np.array([0.0]))
    view = direction(np.array([0.0]), np.array([0.0]))
    truth = texture_truth(tile, light, view, texels=16, spp=16)
    assert sum(name.startswith(f"{tile.parts[0].name}[") for name in truth.names) == 8
    rendered = np.pi * truth_btf(tile, light, view, texels=16, spp=16).astype(np.float64)
    lit = rendered.sum(axis=-1) > 0.1
    error = np.abs(truth.reflectance - rendered).sum(axis=-1)[lit] / rendered.sum(axis=-1)[lit]
    assert np.median(error) < 1e-3 and error.max() < 0.02
