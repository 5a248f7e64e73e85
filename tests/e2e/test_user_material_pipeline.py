"""A user's materials made from files only go through the gonioreflectometer twin: ``spectwin
material examples`` writes a mesh with a spectral EXR texture (printed_tile) and an sRGB photo
with three measured spectra (painted_card); ``spectwin material check`` previews one; each is
captured at three direction pairs (the full reduced 13 x 13 sampling is in BENCHMARKS.md),
processed into a BTF and evaluated against its truth texel by texel (Eq. 6.8, Delta E94)."""

import numpy as np
import pytest

from recon.btf.specular_lobe import microfacet_specular
from recon.calibration.gonio import GonioCalibration
from twin.gonio.capture import GonioPairs, run_gonio_measurement
from twin.materials.user import PATCH_HEIGHT_M
from twin.render.material_preview import PREVIEW_PAIRS_DEG
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory, invoke_json):
    root = tmp_path_factory.mktemp("user")
    written = invoke_json("material", "examples", "--out", root / "materials", "--json")
    invoke_json("capture", "gonio-calibration", root / "cal.capture.zarr", "--json")
    invoke_json("calibrate", root / "cal.capture.zarr", "--out", root / "cal.json", "--json")
    exposures = GonioCalibration.load(root / "cal.json").planned_exposure_s
    pairs = GonioPairs(
        load_rig("gonio"),
        direction(np.array([30.0, 45.0, 60.0]), np.array([0.0, 90.0, 180.0])),
        direction(np.array([0.0, 30.0, 60.0]), np.array([0.0, 200.0, 135.0])),
    )
    results = {}
    for path in written["materials"]:
        name = path.rsplit("/", 1)[-1].removesuffix(".yaml")
        capture, btf = root / f"{name}.capture.zarr", root / f"{name}.btf.zarr"
        run_gonio_measurement(capture, exposures, material=path, pairs=pairs, seed=3)
        invoke_json("process", capture, "--calibration", root / "cal.json", "--out", btf, "--json")
        figure = root / f"{name}.png"
        results[name] = invoke_json("evaluate", btf, "--figure", figure, "--json")
    return root, written, results


def test_material_check_previews_a_user_material(evaluated, invoke_json):
    root, written, _ = evaluated
    tile = written["materials"][0]
    checked = invoke_json(
        "material", "check", tile, "--out", root / "preview", "--texels", 32, "--json"
    )
    assert checked["parts"]["tile"] == {"faces": 4608, "texels": "32x32", "bsdf": "rough plastic"}
    assert (root / "preview" / "material_preview.png").stat().st_size > 20_000
    # Lit from 30 degrees the tile's texture (eight measured reflectances, shaded 0.85-1) has a
    # mean reflectance factor between its darkest and brightest spectra's.
    assert 0.1 < checked["mean_reflectance_factor_per_pair"][0] < 0.5


def test_material_check_previews_a_clear_film_as_its_microfacet_lobe(tmp_path, invoke_json):
    """A clear rough dielectric film (index 1.5, Beckmann roughness 0.3) alone, a flat patch:
    the preview's reflectance factor at each pair is pi times the microfacet lobe with the
    film's Fresnel reflectance (recon.btf.specular_lobe, Walter et al. in numpy) times nothing
    else: no diffuse base, and its transmitted light does not come back. The patch lies 0.3 mm
    above the sample plane, so an oblique view sees it shifted and misses a sliver of it."""
    (tmp_path / "film.yaml").write_text(
        "name: film\nmaterial: user\nsize_m: 0.02\nparts:\n  - name: film\n"
        "    bsdf: {type: rough_dielectric, roughness: 0.3}\n"
    )
    checked = invoke_json(
        "material", "check", tmp_path / "film.yaml", "--out", tmp_path, "--texels", 8, "--json"
    )
    assert checked["parts"]["film"] == {"faces": 2, "texels": "1x1", "bsdf": "rough dielectric"}
    (light, view) = np.array(PREVIEW_PAIRS_DEG).transpose(1, 0, 2)
    view_dirs = direction(view[:, 0], view[:, 1])
    lobe = microfacet_specular(direction(light[:, 0], light[:, 1]), view_dirs, 0.3, True)
    shift = PATCH_HEIGHT_M * view_dirs[:, :2] / view_dirs[:, 2:] / 0.02  # in sample sizes
    seen = np.prod(1 - np.abs(shift), axis=1)
    np.testing.assert_allclose(
        checked["mean_reflectance_factor_per_pair"], np.pi * lobe * seen, atol=2e-3
    )
    assert np.pi * lobe.max() > 0.02  # the comparison is not between zeros


@pytest.mark.parametrize(
    ("name", "median_pct", "mean_delta_e"),
    # Measured: printed_tile median 3.6 %, mean Delta E94 2.6; painted_card 1.8 %, 1.4. Texels
    # at the texture's edges blur in the oblique views (the 95th percentiles are 44 % and 26 %).
    [("printed_tile", 5.0, 3.5), ("painted_card", 3.0, 2.0)],
)
def test_user_materials_captured_by_the_twin_match_their_truth(
    evaluated, name, median_pct, mean_delta_e
):
    root, _, results = evaluated
    result = results[name]
    assert result["pairs_compared"] == 3 and result["texels_compared"] > 10_000
    assert result["median_relative_error_texels_pct"] < median_pct
    assert result["mean_delta_e94_texels"] < mean_delta_e
    assert result["median_delta_e94_texels"] < 1.0
    assert result["max_corner_error_px"] < 0.25
    assert (root / f"{name}.png").stat().st_size > 20_000
