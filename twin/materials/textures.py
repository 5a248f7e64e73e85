"""Noise-free spectral images of a material as weights of its spectral basis per texel.

:func:`twin.render.truth.texture_truth` renders them; the dome's cameras
(:mod:`twin.dome.capture`) integrate them; this module holds only the container, so that code
which reads textures needs no renderer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MATERIAL_TEXEL_REFLECTANCE", "TextureTruth"]

MATERIAL_TEXEL_REFLECTANCE = 0.01
"""Texels whose true mean reflectance is below this show no material (the gaps between Lego
bricks, seen through to the void, and full shadows): Eq. 6.8 is meaningless there, so the
error statistics leave them out."""


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
        ``(n_basis,)`` part names (``"part[i]"`` for the spectra of a textured part),
        ``"surface"`` for the flat spectrum.
    """

    weights: np.ndarray
    fine_basis: np.ndarray
    band_basis: np.ndarray
    names: tuple[str, ...]

    @property
    def reflectance(self) -> np.ndarray:
        """``(n_images, H, W, len(DEFAULT_GRID))`` reflectance factors: the truth."""
        return self.weights @ self.band_basis
