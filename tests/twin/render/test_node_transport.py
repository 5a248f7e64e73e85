"""Light transport at the wavelength nodes (twin.render.node_transport): its band integrals are
exact for spectra linear between the nodes, and its renders agree with Mitsuba's own spectral
path tracer, without the tracer's per-band sampling noise."""

import drjit as dr
import numpy as np
import pytest

from recon.btf.specular_lobe import microfacet_specular
from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.gonio.render import GonioScene, gonio_camera, gonio_lamp, pose_matrix
from twin.materials import load_material
from twin.materials.geometry import box
from twin.materials.sample_holder import holder_parts
from twin.materials.surfaces import SurfacePart
from twin.render import node_transport
from twin.render.node_transport import (
    NODES_NM,
    DistantLight,
    NodeScene,
    ParallelCamera,
    PinholeRays,
    PointLight,
    PointLights,
    node_weights,
)
from twin.render.scene import render_view
from twin.render.shapes import part_bsdf
from twin.rigs.gonio_kinematics import solve_pairs
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor


def _ramp(first: float, last: float) -> SampledSpectra:
    """A reflectance linear in wavelength on the render grid."""
    return SampledSpectra(FINE_GRID, np.linspace(first, last, FINE_GRID.size))


def test_node_weights_integrate_a_spectrum_linear_between_the_nodes_exactly(rng):
    at_nodes = rng.uniform(0.05, 0.95, NODES_NM.size)
    fine = np.interp(FINE_GRID.wavelengths_nm, NODES_NM, at_nodes)  # constant beyond the ends
    bands = LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)
    expected = np.trapezoid(bands.values * fine, FINE_GRID.wavelengths_nm, axis=1)
    np.testing.assert_allclose(at_nodes @ node_weights(bands), expected, rtol=1e-9)


def _mitsuba_path_tracer_rates(config, pose, material, pixels, spp):
    """The gonio rates as Mitsuba's spectral path tracer renders them (max_depth 3), one render
    per lamp part with the lamp's spectrum in the film (twin.render.scene.render_view)."""
    sensor = Sensor(config.camera.definition)
    bands = LiquidCrystalTunableFilter.varispec(config.camera.filter).transmission(FINE_GRID)
    channels = sensor.electron_responses(FINE_GRID, bands)
    lamp, position = gonio_lamp(config, pose.lamp_id)
    spectra = lamp.spectral_parts(FINE_GRID)
    camera = gonio_camera(config, pose.rail_deg, pixels)
    parts = holder_parts() + list(material.parts)
    return np.stack(
        [
            render_view(
                parts,
                pose_matrix(pose),
                camera,
                channels,
                position,
                spectra.row(name),
                spp=spp,
                seed=5,
            )
            for name in spectra.names
        ]
    )


@pytest.mark.render
@pytest.mark.parametrize(
    "part",
    [
        SurfacePart("matte", box((0, 0, -0.01), (0.2, 0.2, 0.02)), _ramp(0.1, 0.8)),
        SurfacePart("glossy", box((0, 0, -0.01), (0.2, 0.2, 0.02)), _ramp(0.7, 0.2), 0.1),
        SurfacePart("silver", box((0, 0, -0.01), (0.2, 0.2, 0.02)), _ramp(0.5, 0.5), 0.2, "Ag"),
        SurfacePart(
            "clear", box((0, 0, -0.01), (0.2, 0.2, 0.02)), _ramp(1, 1), 0.2, dielectric_ior=1.7
        ),
    ],
    ids=lambda part: part.name,
)
def test_a_flat_part_reflects_what_mitsubas_own_bsdf_gives_at_each_node(part):
    """A distant light and parallel rays see one BSDF configuration in every pixel: the node
    radiance must be Mitsuba's BSDF of the part (its real reflectance or metal), evaluated at
    the node's wavelength, times the cosine: the unit-reflectance lobes times the spectral
    factors reproduce it."""
    import mitsuba as mi

    light, view = direction(35.0, 20.0), direction(25.0, 190.0)
    radiance = NodeScene([part]).transport(
        ParallelCamera(view, 0.05, 4), DistantLight(light), spp=4, bounces=0
    )
    bsdf = mi.load_dict(part_bsdf(part))
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.sh_frame = mi.Frame3f(mi.Normal3f(0.0, 0.0, 1.0))
    si.wi = mi.Vector3f(*map(float, view))
    expected = []
    for group in NODES_NM.reshape(-1, 3):  # four wavelengths a Mitsuba spectrum, 81 = 27 x 3
        si.wavelengths = mi.Spectrum(*map(float, group), float(group[-1]))
        value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*map(float, light)))
        expected += [float(value[i][0]) for i in range(3)]
    np.testing.assert_allclose(radiance, np.broadcast_to(expected, radiance.shape), rtol=2e-5)


@pytest.mark.render
def test_a_clear_dielectric_reflects_the_microfacet_lobe_of_its_fresnel_reflectance():
    """A clear dielectric with no base (Mitsuba ``roughdielectric``) under a distant light
    reflects, at every node alike, the Beckmann microfacet lobe of Walter et al. with the
    Fresnel reflectance of index 1.5 (recon.btf.specular_lobe, written from the paper in numpy)
    times the light's cosine; its transmitted part does not come back."""
    part = SurfacePart(
        "clear", box((0, 0, -0.01), (0.2, 0.2, 0.02)), _ramp(1, 1), 0.15, dielectric_ior=1.5
    )
    scene = NodeScene([part])
    light = direction(40.0, 0.0)
    for view in (direction(35.0, 180.0), direction(50.0, 170.0), direction(10.0, 90.0)):
        radiance = scene.transport(
            ParallelCamera(view, 0.05, 2), DistantLight(light), spp=4, bounces=0
        )
        lobe = microfacet_specular(light, view, 0.15, beckmann=True) * light[2]
        np.testing.assert_allclose(radiance, lobe, rtol=1e-4)


@pytest.mark.render
def test_a_floor_lit_past_a_clear_slab_is_seen_through_it():
    """Parallel rays straight down through a clear slab 0.2 mm thick, 1 mm above a white floor,
    the light at 60 degrees: the slab's shadow falls 1.6 mm aside, so the floor under the slab's
    +x edge is lit, and seen through both faces of the slab three interactions on (Fresnel
    transmission 0.96 at each face for index 1.5: 0.92 of the bare floor's radiance); with no
    bounce only the slab's own faint reflection is seen."""
    slab = SurfacePart(
        "slab", box((0, 0, 0.001), (0.02, 0.02, 0.0002)), _ramp(1, 1), 0.05, dielectric_ior=1.5
    )
    floor = SurfacePart("floor", box((0, 0, -0.005), (0.2, 0.2, 0.01)), _ramp(0.8, 0.8))
    scene = NodeScene([slab, floor])
    light = DistantLight(direction(60.0, 0.0))
    camera = ParallelCamera(np.array([0.0, 0.0, 1.0]), 0.01, 40)  # the slab's square, 0.5 mm
    bare = 0.8 / np.pi * np.cos(np.radians(60.0))
    strip = np.s_[:, -2:, 40]  # x from 9 to 10 mm: the lit side
    seen = scene.transport(camera, light, spp=16, bounces=3)[strip]
    assert seen.mean() / bare == pytest.approx(0.92, abs=0.02)
    assert scene.transport(camera, light, spp=16, bounces=0)[strip].max() < 0.01 * bare


@pytest.mark.render
@pytest.mark.parametrize(
    ("name", "light", "view"),
    [
        ("colorchecker16", (45.0, 0.0), (45.0, 180.0)),  # glossy fields near the mirror direction
        ("lego", (60.0, 0.0), (45.0, 200.0)),  # bricks 10 mm tall light and shadow each other
    ],
)
def test_renders_agree_with_mitsubas_spectral_path_tracer(name, light, view):
    config = load_rig("gonio")
    pose = solve_pairs(config, direction(*light)[None], direction(*view)[None]).poses[0]
    material = load_material(name)
    nodes = GonioScene(config, material).part_rates(pose, pixels=40, spp=64, seed=1)
    tracer = _mitsuba_path_tracer_rates(config, pose, material, 40, 1024)
    # Per lamp part and band over the whole field. The tracer's band noise (about 9 % per pixel
    # and band at 1024 spp) averages to about 1 % per band; summed over the bands, no bias.
    ratio = nodes.sum(axis=(1, 2)) / tracer.sum(axis=(1, 2))
    np.testing.assert_allclose(ratio, 1.0, atol=0.03)
    np.testing.assert_allclose(
        nodes.sum(axis=(1, 2, 3)) / tracer.sum(axis=(1, 2, 3)), 1.0, atol=0.005
    )


@pytest.mark.render
def test_a_seed_gives_the_same_image_on_any_number_of_threads():
    config = load_rig("gonio")
    pose = solve_pairs(config, direction(30.0, 0.0)[None], direction(15.0, 180.0)[None]).poses[0]
    scene = GonioScene(config, load_material("red_fabric"))
    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        one = scene.part_rates(pose, pixels=48, spp=16, seed=3)
    finally:
        dr.set_thread_count(threads)
    again = scene.part_rates(pose, pixels=48, spp=16, seed=3)
    np.testing.assert_array_equal(one, again)
    assert not np.array_equal(one, scene.part_rates(pose, pixels=48, spp=16, seed=4))


@pytest.mark.render
def test_an_image_does_not_depend_on_how_it_is_cut_into_launches(monkeypatch):
    """A pixel's random numbers follow from the seed, the pixel and the sample alone: rendered
    in launches of 37 pixels, or a pass of lamps in launches of 23, the images are the same as
    in one launch (a pass's pixels per launch depend on its lamps, so an LED's image does not
    depend on the others of its pass however large the image)."""
    scene = NodeScene(holder_parts() + list(load_material("lego").parts))
    camera = _oblique_view(24)
    lamps = np.array([[0.3, 0.2, 0.8], [-0.4, 0.1, 0.7]])
    weights = node_weights(
        LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)
    ).astype(np.float32)
    whole = scene.transport(camera, PointLight(lamps[0]), spp=16, seed=5)
    each = scene.transport_each(camera, lamps, weights, spp=16, seed=5)
    monkeypatch.setattr(node_transport, "_MAX_LANES", 37 * 16)
    monkeypatch.setattr(node_transport, "_EACH_LANES", 23 * 16)
    np.testing.assert_array_equal(
        scene.transport(camera, PointLight(lamps[0]), spp=16, seed=5), whole
    )
    cut = scene.transport_each(camera, lamps, weights, spp=16, seed=5)
    np.testing.assert_allclose(cut, each, rtol=1e-5, atol=1e-7 * each.max())  # sums' rounding


@pytest.mark.render
def test_a_group_of_point_lights_renders_as_the_sum_of_its_lamps():
    """The Lego bricks on the holder under three lamps at once against the sum of three
    one-lamp renders: equal (float rounding) in the direct light, where every lamp is sampled;
    with a bounce, where one lamp is chosen at random, equal in the image's mean to 1.5 %
    (measured 0.4 %: the random choice's noise in the light after a bounce)."""
    scene = NodeScene(holder_parts() + list(load_material("lego").parts))
    camera = PinholeRays(
        np.array([0.0, 0.0, 1.0]),
        np.array([-1.0, 0, 0]),
        np.array([0, 1.0, 0]),
        np.array([0, 0, -1.0]),
        0.05,
        32,
    )
    lamps = np.array([[0.3, 0.2, 0.8], [-0.4, 0.1, 0.7], [0.0, -0.5, 0.6]])
    for bounces in (0, 1):
        group = scene.transport(camera, PointLights(lamps), spp=16, seed=3, bounces=bounces)
        single = sum(
            scene.transport(camera, PointLight(lamp), spp=16, seed=3, bounces=bounces)
            for lamp in lamps
        )
        if bounces == 0:
            np.testing.assert_allclose(group, single, rtol=1e-5, atol=1e-6 * single.max())
        else:
            assert group.mean() == pytest.approx(single.mean(), rel=0.015)


def _oblique_view(pixels: int) -> PinholeRays:
    """A camera 45 degrees off the holder's normal, seeing the sample and the holder's walls."""
    return PinholeRays(
        np.array([0.0, -0.7, 0.7]),
        np.array([-1.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 1.0]) / np.sqrt(2),
        np.array([0.0, 1.0, -1.0]) / np.sqrt(2),
        0.06,
        pixels,
    )


@pytest.mark.render
@pytest.mark.parametrize(
    ("material", "bounces"),
    [("lego", 1), ("wallpaper", 1), ("colorchecker16", 2), ("lego", 0), ("red_fabric", 1)],
)
def test_each_lamp_of_one_pass_renders_as_that_lamp_alone(material, bounces):
    """transport_each traces the camera's paths once for every lamp; each lamp's channels are
    the one-lamp render with the same seed projected on the channels, to float rounding: on the
    Lego bricks, the wallpaper and the colour checker (two bounces) on the holder, directly lit
    only, and the red fabric (its metal threads render lamp by lamp). One lamp's image does not
    depend on the others of its pass."""
    scene = NodeScene(holder_parts() + list(load_material(material).parts))
    camera = _oblique_view(24)
    lamps = np.array([[0.3, 0.2, 0.8], [-0.4, 0.1, 0.7], [0.0, -0.5, 0.6], [0.5, -0.5, 0.2]])
    bands = LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)
    weights = node_weights(bands).astype(np.float32)
    each = scene.transport_each(camera, lamps, weights, spp=16, seed=5, bounces=bounces)
    assert each.shape == (4, 24, 24, weights.shape[1])
    for lamp, image in zip(lamps, each, strict=True):
        alone = scene.transport(camera, PointLight(lamp), spp=16, seed=5, bounces=bounces)
        expected = alone.astype(np.float32) @ weights
        np.testing.assert_allclose(image, expected, rtol=1e-4, atol=1e-5 * expected.max())
    first = scene.transport_each(camera, lamps[2:3], weights, spp=16, seed=5, bounces=bounces)
    np.testing.assert_allclose(first[0], each[2], rtol=1e-6, atol=1e-7 * each.max())


@pytest.mark.render
def test_each_lamp_renders_only_the_channels_it_is_asked_for():
    """Lamps that want other channels (the dome's spectral camera: each LED's scheduled bands)
    get those channels in that order, the same values as the pass of every channel."""
    scene = NodeScene(holder_parts() + list(load_material("wallpaper").parts))
    camera = _oblique_view(16)
    lamps = np.array([[0.3, 0.2, 0.8], [-0.4, 0.1, 0.7], [0.0, -0.5, 0.6]])
    weights = node_weights(
        LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)
    ).astype(np.float32)
    every = scene.transport_each(camera, lamps, weights, spp=4, seed=2)
    wanted = [(4, 20), (7,), (4, 20)]
    chosen = scene.transport_each(camera, lamps, weights, spp=4, seed=2, channels=wanted)
    assert chosen.shape == (3, 16, 16, 2)
    for lamp, channels in enumerate(wanted):
        np.testing.assert_allclose(
            chosen[lamp, ..., : len(channels)], every[lamp][..., channels], rtol=1e-5
        )
    assert not chosen[1, ..., 1].any()
    with pytest.raises(InputError, match="channels: expected one list per lamp"):
        scene.transport_each(camera, lamps, weights, channels=[(1,)])
