"""Choice of the Mitsuba variant (twin.render.variant) for the LLVM versions a machine may have."""

import os
import subprocess
import sys

import drjit as dr
import numpy as np
import pytest

from recon.errors import InputError
from twin.render.variant import (
    DEFAULT_VARIANT,
    FALLBACK_VARIANT,
    GPU_VARIANT,
    choose_variant,
    llvm_version,
)


@pytest.mark.parametrize(
    ("found", "expected"),
    [
        ((19, 1, 7), DEFAULT_VARIANT),
        ((16, 0, 6), DEFAULT_VARIANT),
        ((15, 0, 6), FALLBACK_VARIANT),
        ((14, 0, 6), FALLBACK_VARIANT),
        (None, FALLBACK_VARIANT),
    ],
)
def test_llvm_older_than_16_falls_back_to_scalar_spectral(found, expected):
    variant, reason = choose_variant(None, found)
    assert variant == expected and reason


def test_requested_variant_wins_and_must_be_spectral():
    assert choose_variant("scalar_spectral", (19, 1, 7))[0] == "scalar_spectral"
    with pytest.raises(InputError, match="spectral"):
        choose_variant("llvm_ad_rgb", (19, 1, 7))
    with pytest.raises(InputError, match="expected one of"):
        choose_variant("vulkan_spectral", (19, 1, 7))


def test_this_machine_has_a_usable_llvm():
    # The bootstrap installs libllvm19 where Debian's LLVM is older than 16.
    found = llvm_version()
    assert found is not None and found[0] >= 16


def test_a_gpu_is_used_where_cuda_is_found_unless_a_variant_is_requested():
    assert choose_variant(None, (19, 1, 7), cuda=True) == (
        GPU_VARIANT,
        "CUDA found: renders on the GPU",
    )
    assert choose_variant(None, None, cuda=True)[0] == GPU_VARIANT
    assert choose_variant(DEFAULT_VARIANT, (19, 1, 7), cuda=True)[0] == DEFAULT_VARIANT
    assert choose_variant(None, (19, 1, 7), cuda=False)[0] == DEFAULT_VARIANT


_GPU_SCRIPT = """
import sys
import numpy as np
from twin.materials import load_material
from twin.materials.sample_holder import holder_parts
from twin.render.node_transport import NodeScene, PinholeRays
from twin.render.variant import activate
print(activate().variant, file=sys.stderr)
scene = NodeScene(holder_parts() + list(load_material("lego").parts))
camera = PinholeRays(np.array([0.0, -0.7, 0.7]), np.array([-1.0, 0, 0]),
                     np.array([0, 1.0, 1.0]) / 2**0.5, np.array([0, 1.0, -1.0]) / 2**0.5, 0.06, 32)
lamps = np.array([[0.3, 0.2, 0.8], [-0.4, 0.1, 0.7]])
np.save(sys.argv[1], scene.transport_each(camera, lamps, np.eye(81, 3, dtype=np.float32), spp=16))
"""


@pytest.mark.render
@pytest.mark.skipif(
    not dr.has_backend(dr.JitBackend.CUDA), reason="no CUDA GPU on this machine (Dr.Jit finds none)"
)
def test_the_gpu_renders_what_the_cpu_renders(tmp_path):
    """Where Dr.Jit finds CUDA, spectwin renders on cuda_ad_spectral by default; a pass of two
    lamps over the Lego bricks equals the CPU's (llvm_ad_spectral) to float tolerance."""
    results = {}
    for variant in ("", DEFAULT_VARIANT):
        out = tmp_path / f"{variant or 'default'}.npy"
        env = {**os.environ, "SPECTWIN_VARIANT": variant}
        run = subprocess.run(
            [sys.executable, "-c", _GPU_SCRIPT, str(out)], env=env, capture_output=True, text=True
        )
        assert run.returncode == 0, run.stderr
        results[run.stderr.strip().splitlines()[-1]] = np.load(out)
    assert set(results) == {GPU_VARIANT, DEFAULT_VARIANT}
    gpu, cpu = results[GPU_VARIANT], results[DEFAULT_VARIANT]
    np.testing.assert_allclose(gpu, cpu, rtol=1e-3, atol=1e-4 * cpu.max())
