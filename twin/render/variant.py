"""Choose, activate and report the Mitsuba variant: the one place that calls ``mi.set_variant``.

Where Dr.Jit finds CUDA (an NVIDIA GPU and its driver), ``cuda_ad_spectral`` is used: the
renders (the node transport of both rigs, the BTF BSDF, the Figure 4.6 renders) run on the GPU.
Elsewhere ``llvm_ad_spectral`` is the default. It needs a system libLLVM 16 or newer: Dr.Jit 1.5
crashes with Debian's LLVM 14/15 (ARCHITECTURE.md, "Mitsuba notes"), so with an older or missing
LLVM the slower ``scalar_spectral`` variant is used and a warning says why. ``SPECTWIN_VARIANT``
overrides the choice (``llvm_ad_spectral`` keeps a GPU machine on its CPUs);
``SPECTWIN_THREADS`` sets Dr.Jit's thread count on the CPU (default: all cores).
"""

from __future__ import annotations

import os
import warnings
from dataclasses import asdict, dataclass

import drjit as dr
import mitsuba as mi

from recon.errors import InputError

__all__ = [
    "DEFAULT_VARIANT",
    "FALLBACK_VARIANT",
    "GPU_VARIANT",
    "VariantReport",
    "activate",
    "choose_variant",
    "llvm_version",
]

DEFAULT_VARIANT = "llvm_ad_spectral"
GPU_VARIANT = "cuda_ad_spectral"
FALLBACK_VARIANT = "scalar_spectral"
MINIMUM_LLVM_MAJOR = 16

_active: VariantReport | None = None


@dataclass(frozen=True)
class VariantReport:
    """What was chosen and why: variant name, LLVM version found, thread count, reason."""

    variant: str
    llvm_version: str | None
    threads: int
    reason: str

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def llvm_version() -> tuple[int, int, int] | None:
    """Version of the libLLVM that Dr.Jit loads, or ``None`` when it finds none."""
    if not dr.has_backend(dr.JitBackend.LLVM):
        return None
    return tuple(dr.detail.llvm_version())


def choose_variant(
    requested: str | None, found: tuple[int, int, int] | None, *, cuda: bool = False
) -> tuple[str, str]:
    """The variant and why: ``requested`` (``SPECTWIN_VARIANT``) if given, else the GPU's where
    ``cuda`` (Dr.Jit found CUDA), else by the LLVM version ``found`` (module docstring)."""
    if requested:
        if requested not in mi.variants():
            raise InputError(
                f"SPECTWIN_VARIANT: expected one of {mi.variants()}, got {requested!r}"
            )
        if not requested.endswith(("spectral", "spectral_polarized")):
            raise InputError(
                f"SPECTWIN_VARIANT: spectwin renders spectrally, expected a *_spectral variant, "
                f"got {requested!r}"
            )
        return requested, "requested by SPECTWIN_VARIANT"
    if cuda:
        return GPU_VARIANT, "CUDA found: renders on the GPU"
    if found is None:
        return FALLBACK_VARIANT, "no libLLVM found"
    if found[0] < MINIMUM_LLVM_MAJOR:
        return FALLBACK_VARIANT, (
            f"libLLVM {found[0]} is older than {MINIMUM_LLVM_MAJOR} (install libllvm19)"
        )
    return DEFAULT_VARIANT, f"libLLVM {found[0]} found"


def activate() -> VariantReport:
    """Select the variant once per process and return the report (later calls return it too)."""
    global _active
    if _active is not None:
        return _active
    found = llvm_version()
    variant, reason = choose_variant(
        os.environ.get("SPECTWIN_VARIANT"), found, cuda=bool(dr.has_backend(dr.JitBackend.CUDA))
    )
    if variant == FALLBACK_VARIANT and "SPECTWIN_VARIANT" not in reason:
        warnings.warn(
            f"spectwin uses the slow Mitsuba variant {FALLBACK_VARIANT}: {reason}", stacklevel=2
        )
    threads_text = os.environ.get("SPECTWIN_THREADS", "")
    if threads_text:
        if not threads_text.isdigit() or int(threads_text) < 1:
            raise InputError(f"SPECTWIN_THREADS: expected a positive integer, got {threads_text!r}")
        dr.set_thread_count(int(threads_text))
    mi.set_variant(variant)
    _active = VariantReport(
        variant=variant,
        llvm_version=".".join(map(str, found)) if found else None,
        threads=dr.thread_count(),
        reason=reason,
    )
    return _active
