"""The plugins' sizes are opaque to Dr.Jit: a BTF or an environment map of other sizes renders
with the kernels already compiled (a new kernel costs seconds to compile: 2-8 s each for the
path tracer's with a BTF, 11 s for a validation of another texel count before)."""

import gc

import numpy as np
import pytest

from recon.spectra import DEFAULT_GRID, WavelengthGrid
from twin.render.plugins.btf_bsdf import btf_bsdf, product_table
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.render import load_scene, render_scene
from twin.render.scene import PinholeCamera
from twin.render.truth import band_passbands
from twin.rigs.hemisphere import sattler_directions

pytestmark = pytest.mark.render
# kernels of this many operations or more are the renderer's (thousands of operations, seconds
# to compile); the few-operation kernels that set up a map's sampling distribution take its size
# as a literal and compile in milliseconds
LARGE_KERNEL_OPS = 500
CAMERA = PinholeCamera(np.array([0.0, -3.0, 3.0]), field_of_view_m=2.0, pixels=8)


def _scene(map_height: int, texels: int, direction_step: int) -> dict:
    """A BTF square under a spectral map, both of the given sizes."""
    rng = np.random.default_rng(map_height + texels)
    directions = sattler_directions()[::direction_step]
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    values = rng.uniform(0.05, 0.5, (len(lights), texels, texels, DEFAULT_GRID.size))
    radiance = rng.uniform(0.5, 1.0, (map_height, 2 * map_height, DEFAULT_GRID.size))
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": CAMERA.mitsuba_sensor(
            band_passbands(WavelengthGrid(np.array([450.0, 650.0]))), 2
        ),
        "environment": spectral_envmap(SpectralMap(radiance, DEFAULT_GRID)),
        "square": {
            "type": "rectangle",
            "bsdf": btf_bsdf(product_table(lights, views, values.astype(np.float32), DEFAULT_GRID)),
        },
    }


def _kernels_of(scene: dict) -> tuple[set[str], np.ndarray]:
    """The hashes of the large kernels a render of ``scene`` launched, and the image.

    Unreachable scenes of earlier renders are collected first: a kernel's calls into the
    plugins are numbered by the instances alive in Dr.Jit's registry, so a scene freed by the
    garbage collector between two renders gives the second other numbers, and another kernel.
    """
    import drjit as dr

    gc.collect()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # empties the history
        image = render_scene(scene, seed=1)
        launched = {
            kernel["hash"]
            for kernel in dr.kernel_history()
            if kernel.get("operation_count", 0) >= LARGE_KERNEL_OPS
        }
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    return launched, image


def test_other_btf_and_map_sizes_reuse_the_compiled_kernels():
    first, first_image = _kernels_of(_scene(map_height=4, texels=4, direction_step=6))
    second, second_image = _kernels_of(_scene(map_height=6, texels=7, direction_step=4))
    assert first and second <= first
    # the renders are of the new sizes' data, not the old
    assert np.all(second_image > 0) and not np.allclose(first_image, second_image)


def test_the_plugins_print_their_sizes():
    """The sizes held as opaque values are printed from the plain numbers kept beside them."""
    scene = load_scene(_scene(map_height=4, texels=5, direction_step=6))
    (square,) = scene.shapes()
    assert str(square.bsdf()) == "SpectralBTF[_DecodedSpectra, 5x5]"
    assert str(scene.environment()) == f"SpectralEnvmapEmitter[4 x 8 x {DEFAULT_GRID.size}]"
