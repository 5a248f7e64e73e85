"""Noise-free spectral images of a twin material: part weights per texel times part spectra.

The thesis's chapter 10 simulation starts from spectral reference images :math:`S_{ref}` of a
material under one light and view direction (Eq. 10.10, 10.11). The twin's are rendered by
:func:`twin.render.truth.truth_btf` (Mitsuba, reflectance averaged over 10 nm passbands) and
multiplied
by :math:`\\pi`, so that a white Lambertian surface reads 1 (reflectance factors, as Eq. 6.8's
:math:`\\epsilon = 10^{-3}` assumes).

A spectral render samples wavelengths at random per path, so at 64 spp neighbouring bands of one
texel differ by tens of percent of Monte Carlo noise (two seeds: 34 % mean relative error; 9 % at
1024 spp), which no method could predict from RGB. Each texel is therefore replaced by its
non-negative least-squares fit with the material's part reflectances plus a flat spectrum (the
surface reflection of a dielectric, i.e. highlights): shading, shadowing, highlights and the
mixing of parts within a texel stay, the noise goes. The weights also give the texel's spectrum
on the fine grid, where the cameras integrate it (:mod:`twin.dome.capture`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from recon.errors import SpectwinInputError
from recon.spectra import DEFAULT_GRID, resample
from twin.components import FINE_GRID
from twin.materials import Material, load_material
from twin.render.truth import band_passbands, truth_btf

__all__ = ["TextureTruth", "texture_truth"]


@dataclass(frozen=True)
class TextureTruth:
    """Images of one material as weights of its spectral basis.

    Attributes
    ----------
    weights
        ``(n_images, H, W, n_basis)`` non-negative weight of each basis spectrum per texel.
    fine_basis
        ``(n_basis, len(FINE_GRID))`` the part reflectances and the flat spectrum on
        ``FINE_GRID``.
    band_basis
        ``(n_basis, len(DEFAULT_GRID))`` the same averaged over the 10 nm passbands.
    names
        ``(n_basis,)`` part names, ``"surface"`` for the flat spectrum.
    """

    weights: np.ndarray
    fine_basis: np.ndarray
    band_basis: np.ndarray
    names: tuple[str, ...]

    @property
    def reflectance(self) -> np.ndarray:
        """``(n_images, H, W, len(DEFAULT_GRID))`` reflectance factors: the truth."""
        return self.weights @ self.band_basis


def _basis(material: Material, surface: bool) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    spectra = [
        resample(part.reflectance, FINE_GRID, method="linear").values for part in material.parts
    ]
    names = tuple(part.name for part in material.parts)
    if surface:
        spectra, names = spectra + [np.ones(FINE_GRID.size)], names + ("surface",)
    fine = np.array(spectra)
    passbands = band_passbands(DEFAULT_GRID)
    return fine, fine @ (passbands.values * FINE_GRID.quadrature_weights()).T, names


def texture_truth(
    material: str | Material,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    *,
    texels: int = 48,
    spp: int = 64,
    surface: bool = True,
) -> TextureTruth:
    """Render ``material`` for each (light, view) pair and fit every texel with its basis.

    Parameters
    ----------
    material
        A twin material or its name (``scenes/materials``).
    light_dirs, view_dirs
        ``(n_images, 3)`` unit directions in the sample frame, z up.
    texels
        Texture side in texels.
    spp
        Samples per pixel of the renders.
    surface
        Include the flat spectrum (highlights) in the basis.
    """
    model = load_material(material) if isinstance(material, str) else material
    if texels < 2:
        raise SpectwinInputError(f"texels: expected at least 2, got {texels}")
    btf = np.pi * truth_btf(model, light_dirs, view_dirs, texels=texels, spp=spp)
    fine, bands, names = _basis(model, surface)
    pixels = btf.reshape(-1, btf.shape[-1]).astype(np.float64)
    weights = np.array([optimize.nnls(bands.T, pixel)[0] for pixel in pixels])
    return TextureTruth(weights.reshape(*btf.shape[:-1], len(names)), fine, bands, names)
