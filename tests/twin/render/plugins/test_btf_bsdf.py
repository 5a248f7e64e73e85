"""The BTF BSDF plugin: a BTF sampled from Mitsuba's roughplastic (Lambert + GGX coating) renders
like roughplastic itself (thesis 4.2, Figure 4.6 validation). Specular lobes fitted per texel
(recon.btf.specular_lobe): the lobe is Mitsuba's own roughplastic coating term, the fit recovers
a coating from the twin's 13 x 13 sampling (only its mirror pairs see the highlight), and the
plugin adds it to the interpolated residual."""

import numpy as np
import pytest

from recon.btf.compression import compress_btf
from recon.btf.specular_lobe import fit_specular_lobes, microfacet_specular
from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.render.plugins.btf_bsdf import (
    BTFTable,
    barycentric,
    btf_bsdf,
    compressed_product_table,
    hemisphere_lookup,
    interpolate_table,
    product_table,
)
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.render import render_scene
from twin.render.spectra import irregular_spectrum, specfilm
from twin.render.truth import band_passbands
from twin.render.variant import activate
from twin.rigs.hemisphere import sattler_directions

CENTRES_NM = np.array([450.0, 550.0, 650.0])


def test_barycentric_lookup_reproduces_linear_functions_inside_the_measured_hull():
    directions = sattler_directions()
    indices, weights = hemisphere_lookup(directions, resolution=64)
    np.testing.assert_allclose(weights.sum(axis=2), 1.0, atol=1e-9)
    centres = -1 + (np.arange(64) + 0.5) * 2 / 64
    x, y = np.meshgrid(centres, centres)
    inside = np.hypot(x, y) < np.sin(np.radians(70))  # well inside the 75 degree ring
    linear = 0.3 + 2.0 * directions[:, 0] - 1.5 * directions[:, 1]
    interpolated = (linear[indices] * weights).sum(axis=2)
    np.testing.assert_allclose(interpolated[inside], (0.3 + 2.0 * x - 1.5 * y)[inside], atol=1e-9)


def test_directions_on_one_line_interpolate_by_the_nearest_direction():
    directions = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)], [-0.5, 0.0, np.sqrt(0.75)]])
    indices, weights = barycentric(directions, np.array([[0.4, 0.1], [-0.1, 0.0]]))
    np.testing.assert_array_equal(indices[:, 0], [1, 0])
    np.testing.assert_array_equal(weights, [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


def test_product_table_fills_an_unmeasured_pair_from_the_nearest_view_of_its_light():
    lights = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)]])
    views = np.array([[0.5, 0.0, np.sqrt(0.75)], [0.0, 0.6, 0.8], [0.0, 0.6, 0.8]])
    reflectance = np.arange(3, dtype=np.float32)[:, None, None, None] * np.ones((3, 1, 1, 33))
    table = product_table(lights, views, reflectance, DEFAULT_GRID)
    assert table.values.shape == (2, 2, 1, 1, 33)
    light = int(np.argmax(table.light_dirs[:, 0]))  # the oblique light has one view measured
    assert np.all(table.values[light] == 2.0)
    with pytest.raises(InputError, match="n_lights, n_views"):
        BTFTable(table.light_dirs, table.view_dirs, table.values[:, :1], DEFAULT_GRID)


def _roughplastic():
    reflectance = 0.2 + 0.6 * np.exp(-0.5 * ((FINE_GRID.wavelengths_nm - 600) / 40) ** 2)
    return {
        "type": "roughplastic",
        "diffuse_reflectance": irregular_spectrum(SampledSpectra(FINE_GRID, reflectance)),
        "alpha": 0.3,
    }


def _sampled_btf(analytic: dict) -> BTFTable:
    """The BRDF of ``analytic`` at Sattler's 81 x 81 directions and the 33 bands, 2 x 2 texels."""
    import drjit as dr
    import mitsuba as mi

    bsdf = mi.load_dict(analytic)
    directions = sattler_directions()
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    values = np.zeros((len(directions), len(directions), 2, 2, DEFAULT_GRID.size), np.float32)
    for band, wavelength in enumerate(DEFAULT_GRID.wavelengths_nm):
        si = dr.zeros(mi.SurfaceInteraction3f, len(lights))
        si.wi = mi.Vector3f(*views.T)
        si.wavelengths = mi.UnpolarizedSpectrum(wavelength)
        value = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*lights.T)))[0]
        values[..., band] = (value / lights[:, 2]).reshape(len(directions), -1)[..., None, None]
    return BTFTable(directions, directions, values, DEFAULT_GRID)


@pytest.mark.render
def test_btf_sampled_from_roughplastic_renders_within_2_percent_of_roughplastic():
    activate()
    import mitsuba as mi

    environment = SpectralMap(
        np.tile(np.linspace(0.5, 1.0, DEFAULT_GRID.size), (16, 32, 1)), DEFAULT_GRID
    )

    def render(bsdf: dict | None, seed: int) -> np.ndarray:
        scene = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 3},
            "sensor": {
                "type": "perspective",
                "fov": 30,
                "to_world": mi.ScalarTransform4f.look_at(
                    origin=[0, -4, 3], target=[0, 0, 0], up=[0, 0, 1]
                ),
                "film": specfilm(band_passbands(WavelengthGrid(CENTRES_NM)), 48, 48),
                "sampler": {"type": "independent", "sample_count": 256},
            },
            "environment": spectral_envmap(environment),
            "lamp": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f.look_at(
                    origin=[2, 1, 3], target=[0, 0, 0], up=[0, 0, 1]
                ).scale(0.5),
                "emitter": {
                    "type": "area",
                    "radiance": irregular_spectrum(
                        SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 20.0))
                    ),
                },
            },
        }
        if bsdf is not None:
            scene["sphere"] = {"type": "sphere", "bsdf": bsdf}
        return render_scene(scene, seed)

    analytic = _roughplastic()
    reference = render(analytic, 1)
    sphere = np.abs(render(None, 1) - reference).sum(axis=2) > 1e-6
    measured = render(btf_bsdf(_sampled_btf(analytic)), 1)
    ratio = measured[sphere].mean(axis=0) / reference[sphere].mean(axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)
    # Per pixel the two differ by less than Monte Carlo noise (the reference with another seed).
    noise = np.median(np.abs(render(analytic, 2) - reference)[sphere] / reference[sphere], axis=0)
    difference = np.median(np.abs(measured - reference)[sphere] / reference[sphere], axis=0)
    assert np.all(difference < noise)


def _evaluate(table, wi, wo, uv, wavelengths) -> np.ndarray:
    """The plugin's eval (cosine included) at ``n`` queries, ``(4, n)`` wavelength channels."""
    import drjit as dr
    import mitsuba as mi

    bsdf = mi.load_dict(btf_bsdf(table))
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi, si.uv = mi.Vector3f(*wi.T), mi.Point2f(*uv.T)
    si.wavelengths = mi.UnpolarizedSpectrum(*[mi.Float(w) for w in wavelengths])
    return np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo.T)))


@pytest.mark.parametrize("layout", ["joint", "per_band"])
def test_compressed_btf_renders_what_its_decoded_form_renders(layout):
    """The plugin decodes the spectral PCA factors per lookup (one Dr.Jit loop over the
    components) and holds the brightness decoded: its values equal those of the decoded BTF,
    from a quarter of the memory or less."""
    activate()
    rng = np.random.default_rng(3)
    directions = sattler_directions()[::4]
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    texture = rng.uniform(0.05, 0.5, (1, 8, 8, DEFAULT_GRID.size))
    per_pair = 1 + 0.5 * np.cos(3 * lights[:, 0] - 2 * views[:, 1])[:, None, None, None]
    noise = 1 + 0.1 * rng.normal(size=(len(lights), 8, 8, 1))
    reflectance = (texture * per_pair * noise).astype(np.float32)
    compressed = compress_btf(
        reflectance, DEFAULT_GRID, n_brightness=12, n_spectral=5, layout=layout
    )
    table = compressed_product_table(lights, views, compressed)
    decoded = product_table(lights, views, compressed.decode(), DEFAULT_GRID)
    assert table.nbytes < decoded.nbytes / 4

    n = 4000
    wi, wo = (rng.normal(size=(n, 3)) for _ in range(2))
    for direction in (wi, wo):
        direction[:, 2] = np.abs(direction[:, 2])
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    uv = rng.uniform(size=(n, 2))
    wavelengths = rng.uniform(395, 725, (4, n))
    from_factors = _evaluate(table, wi, wo, uv, wavelengths)
    from_decoded = _evaluate(decoded, wi, wo, uv, wavelengths)
    assert np.abs(from_decoded).max() > 0.05
    np.testing.assert_allclose(from_factors, from_decoded, rtol=1e-4, atol=1e-6)
    # And the texture the numpy path interpolates (spectrophotometer) is the decoded one too.
    light, view = directions[5], directions[9]
    np.testing.assert_allclose(
        interpolate_table(table, light, view), interpolate_table(decoded, light, view), rtol=1e-5
    )


def test_plugin_adds_the_fitted_lobes_to_the_interpolated_residual():
    """Residual plus lobe is the measurement at a measured mirror pair; the plugin's value is
    its value for the residual alone plus the numpy lobe (recon.btf.specular_lobe)."""
    activate()
    lights, views = twin_sampling()
    btf = coated_btf(lights, views)
    table = product_table(lights, views, btf, DEFAULT_GRID, lobes=True)
    assert table.lobes is not None and table.lobes.glossy_fraction == 0.5
    mirror = int(np.argmax(microfacet_specular(lights, views, 0.08, True)))
    np.testing.assert_allclose(
        interpolate_table(table, lights[mirror], views[mirror]), btf[mirror], rtol=1e-5
    )
    rng = np.random.default_rng(5)
    n = 3000
    wi, wo = directions_above(n, rng), directions_above(n, rng)
    uv = np.tile([0.25, 0.75], (n, 1))  # the centre of texel (0, 0): no blending of texels
    wavelengths = rng.uniform(405, 715, (4, n))
    residual = BTFTable(table.light_dirs, table.view_dirs, table.values, DEFAULT_GRID)
    lobe = _evaluate(table, wi, wo, uv, wavelengths) - _evaluate(residual, wi, wo, uv, wavelengths)
    expected = table.lobes.values(wo, wi)[:, 0, 0] * wo[:, 2]
    assert expected.max() > 1.0
    np.testing.assert_allclose(lobe, np.tile(expected, (4, 1)), rtol=1e-3, atol=1e-5)


def directions_above(n: int, rng) -> np.ndarray:
    values = rng.normal(size=(n, 3))
    values[:, 2] = np.abs(values[:, 2]) + 0.05
    return values / np.linalg.norm(values, axis=1, keepdims=True)


@pytest.mark.parametrize(("distribution", "beckmann"), [("beckmann", True), ("ggx", False)])
def test_the_lobe_is_mitsubas_roughplastic_coating_term(distribution, beckmann):
    """Peer: Mitsuba's roughplastic (index 1.5 in vacuum, no diffuse) evaluated for its glossy
    component only, which is the lobe times the cosine of the light."""
    activate()
    import drjit as dr
    import mitsuba as mi

    rng = np.random.default_rng(0)
    light, view = directions_above(2000, rng), directions_above(2000, rng)
    for alpha in (0.08, 0.3):
        bsdf = mi.load_dict(
            {
                "type": "roughplastic",
                "distribution": distribution,
                "alpha": alpha,
                "int_ior": 1.5,
                "ext_ior": 1.0,
                "nonlinear": False,
                "diffuse_reflectance": {"type": "uniform", "value": 0.0},
            }
        )
        si = dr.zeros(mi.SurfaceInteraction3f, len(view))
        si.wi, si.wavelengths = mi.Vector3f(*view.T), mi.UnpolarizedSpectrum(550.0)
        glossy = mi.BSDFContext(mi.TransportMode.Radiance, int(mi.BSDFFlags.GlossyReflection))
        expected = np.array(bsdf.eval(glossy, si, mi.Vector3f(*light.T)))[0]
        ours = microfacet_specular(light, view, alpha, beckmann) * light[:, 2]
        np.testing.assert_allclose(ours, expected, rtol=1e-4, atol=1e-6)


def twin_sampling():
    directions = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 8)))
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    keep = np.einsum("ij,ij->i", lights, views) < 0.999  # the rig cannot measure light = view
    return lights[keep], views[keep]


def coated_btf(lights, views):
    """2 x 2 texels: a coated (Beckmann 0.08, weight 1) and a GGX-coated (0.15, weight 0.6)
    texel over diffuse colours, and two matte ones."""
    colours = np.linspace(0.1, 0.6, DEFAULT_GRID.size) / np.pi
    btf = np.tile(colours, (len(lights), 2, 2, 1))
    btf[:, 1, 0] *= 0.5
    btf[:, 0, 0] += microfacet_specular(lights, views, 0.08, True)[:, None]
    btf[:, 0, 1] += 0.6 * microfacet_specular(lights, views, 0.15, False)[:, None]
    return btf.astype(np.float32)


def test_fit_recovers_coatings_from_the_mirror_pairs_and_leaves_matte_texels_alone():
    lights, views = twin_sampling()
    lobes = fit_specular_lobes(lights, views, coated_btf(lights, views))
    assert lobes.weight[0, 0] == pytest.approx(1.0, rel=0.1)
    assert lobes.roughness[0, 0] == pytest.approx(0.08, rel=0.1)
    assert lobes.weight[0, 1] > 0 and lobes.weight[0, 1] / lobes.roughness[0, 1] ** 2 == (
        pytest.approx(0.6 / 0.15**2, rel=0.15)
    )  # the peaks fix weight / roughness^2
    np.testing.assert_array_equal(lobes.weight[1], 0.0)


def test_fit_keeps_a_coating_hidden_from_some_pairs_and_gives_broad_variation_no_lobe():
    """A raised field's relief hides its highlight from some mirror pairs but adds none: a
    coated texel whose peak is missing at 5 of its 8 mirror pairs at 60 degrees keeps the
    narrow coating; a matte texel that brightens towards grazing (a variation the 30 degree
    steps resolve) gets no lobe."""
    lights, views = twin_sampling()
    btf = coated_btf(lights, views)
    mirror = (np.abs(lights[:, 2] - 0.5) < 1e-6) & (
        np.einsum("ij,ij->i", lights[:, :2], views[:, :2]) < -0.74
    )
    hidden = np.flatnonzero(mirror)[:5]
    btf[hidden, 0, 0] -= microfacet_specular(lights[hidden], views[hidden], 0.08, True)[:, None]
    grazing = 1 + 2 * (1 - lights[:, 2] * views[:, 2])
    btf[:, 1, 1] *= grazing[:, None].astype(np.float32)
    lobes = fit_specular_lobes(lights, views, btf)
    assert np.flatnonzero(mirror).size == 8
    assert lobes.roughness[0, 0] == pytest.approx(0.08, rel=0.1)
    assert lobes.weight[0, 0] == pytest.approx(1.0, rel=0.1)
    assert lobes.weight[1, 1] == 0.0


def test_a_field_edge_whose_peaks_are_mostly_hidden_takes_its_neighbours_lobe():
    """The texel beside a coated one shows the same coating at only one mirror pair (the
    relief hides the others): too little for a fit of its own, enough to confirm the
    neighbour's lobe. The matte texels beside it take none."""
    lights, views = twin_sampling()
    btf = coated_btf(lights, views)[:, :, :1].repeat(2, axis=2)  # (0, 0) and (0, 1) coated
    coating = microfacet_specular(lights, views, 0.08, True)
    seen = np.argmax(coating)
    btf[:, 0, 1] -= np.where(np.arange(len(lights)) == seen, 0.0, coating)[:, None]
    lobes = fit_specular_lobes(lights, views, btf)
    assert lobes.weight[0, 1] == lobes.weight[0, 0] > 0
    assert lobes.roughness[0, 1] == lobes.roughness[0, 0]
    np.testing.assert_array_equal(lobes.weight[1], 0.0)
