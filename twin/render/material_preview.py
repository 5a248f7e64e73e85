"""A preview of a material (``spectwin material check``): its true BTF at three direction
pairs as sRGB images, and its parts' mean spectra.

The pairs are a frontal view under light from 30 degrees, the same view under grazing light
(60 degrees) and an oblique view (60 degrees) near the mirror direction of a 45 degree light, so
that shading, shadows and highlights show. The textures are the truth of
:func:`twin.render.truth.truth_btf` (Mitsuba, 10 nm bands), rendered to sRGB under equal energy.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from recon.preview import spectral_to_srgb
from recon.spectra import DEFAULT_GRID
from twin.materials import Material
from twin.render.truth import truth_btf
from twin.rigs.hemisphere import direction

__all__ = ["PREVIEW_PAIRS_DEG", "MaterialPreview", "preview_material", "write_preview_figure"]

PREVIEW_PAIRS_DEG = (
    ((30.0, 0.0), (0.0, 0.0)),
    ((60.0, 0.0), (0.0, 0.0)),
    ((45.0, 0.0), (60.0, 170.0)),
)
"""``((light theta, phi), (view theta, phi))`` in degrees of the three preview pairs."""


@dataclass(frozen=True)
class MaterialPreview:
    """The true BTF ``(3, texels, texels, 33)`` in 1/sr at :data:`PREVIEW_PAIRS_DEG`."""

    material: Material
    btf: np.ndarray

    def summary(self) -> dict[str, object]:
        reflectance = np.pi * self.btf.mean(axis=(1, 2, 3))
        return {
            "mean_reflectance_factor_per_pair": [round(float(value), 3) for value in reflectance]
        }


def preview_material(material: Material, *, texels: int = 64, spp: int = 16) -> MaterialPreview:
    """Render the preview's true BTF (module docstring)."""
    angles = np.array(PREVIEW_PAIRS_DEG)
    lights = direction(angles[:, 0, 0], angles[:, 0, 1])
    views = direction(angles[:, 1, 0], angles[:, 1, 1])
    return MaterialPreview(material, truth_btf(material, lights, views, texels=texels, spp=spp))


def write_preview_figure(preview: MaterialPreview, path: str | Path) -> Path:
    """The three textures and the parts' mean reflectance spectra, as a PNG."""
    path = Path(path)
    figure = Figure(figsize=(14, 4.2))
    axes = figure.subplots(1, 4)
    for axis, texture, ((light_t, light_p), (view_t, view_p)) in zip(
        axes[:3], preview.btf, PREVIEW_PAIRS_DEG, strict=True
    ):
        axis.imshow(spectral_to_srgb(texture, DEFAULT_GRID))
        axis.set_title(
            f"light ({light_t:.0f}, {light_p:.0f}), view ({view_t:.0f}, {view_p:.0f}) deg",
            fontsize=9,
        )
        axis.axis("off")
    for part in preview.material.parts:
        if part.bsdf_kind in ("rough conductor", "rough dielectric"):
            continue  # no diffuse reflectance: a metal's colour is its own, a dielectric clear
        axes[3].plot(part.reflectance.wavelengths_nm, part.reflectance.values, label=part.name)
    axes[3].set(
        xlabel="wavelength, nm", ylabel="reflectance (a texture's mean)", title="parts", ylim=(0, 1)
    )
    if axes[3].lines:
        axes[3].legend(fontsize=8)
    else:
        axes[3].text(0.5, 0.5, "no diffuse part", ha="center", transform=axes[3].transAxes)
    figure.suptitle(preview.material.name)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    return path
