"""Choice of the Mitsuba variant (twin.render.variant) for the LLVM versions a machine may have."""

import pytest

from recon.errors import SpectwinInputError
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
    with pytest.raises(SpectwinInputError, match="spectral"):
        choose_variant("llvm_ad_rgb", (19, 1, 7))
    with pytest.raises(SpectwinInputError, match="expected one of"):
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
