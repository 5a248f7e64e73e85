"""The demo's spectralization step: an RGB image plus noisy band images (thesis chapter 10).

The dome setting of the thesis in miniature: a twin material's texture
(:func:`twin.studies.spectralization.twin_texture`) seen by an RGB camera (Nikon D70 response
under D65, 1 % noise) and, at every ``band_step``-th band, by a spectral camera whose short
exposures leave ``band_noise`` relative Gaussian noise. :func:`recon.spectralize.spectralize`
fuses them (Eq. 10.12, the band images matched after a Gaussian filter of ``sigma_px``); the
error is Eq. 6.8 and Delta E94 against the texture. The noise is drawn here, not by the sensor
model (the dome's own capture simulation is in ``twin.dome.capture``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recon.metrics import delta_e94, relative_error
from recon.spectra import DEFAULT_GRID
from recon.spectralize.solve import BandImage, spectralize
from twin.studies.spectralization import study_response, twin_texture

__all__ = ["BandSpectralization", "band_image_spectralization"]


@dataclass(frozen=True)
class BandSpectralization:
    """Truth, RGB, the noisy bands used and the reconstruction ``(H, W, K)``, with errors."""

    truth: np.ndarray
    rgb: np.ndarray
    bands: np.ndarray
    band_values: np.ndarray
    cube: np.ndarray
    relative_error_pct: np.ndarray
    delta_e94: np.ndarray

    def summary(self) -> dict[str, float]:
        return {
            "texels": int(self.truth.shape[0]),
            "band_images": int(self.bands.size),
            "mean_relative_error_pct": float(self.relative_error_pct.mean()),
            "mean_delta_e94": float(self.delta_e94.mean()),
            "noisy_band_error_pct": float(
                relative_error(self.band_values, self.truth[..., self.bands]).mean()
            ),
        }


def band_image_spectralization(
    material: str = "wallpaper",
    *,
    texels: int = 48,
    band_step: int = 3,
    band_noise: float = 0.1,
    rgb_noise: float = 0.01,
    sigma_px: float = 2.0,
    seed: int = 0,
) -> BandSpectralization:
    """Reconstruct ``material``'s texture from RGB and noisy band images (module docstring)."""
    rng = np.random.default_rng(seed)
    truth = twin_texture(material, texels=texels)
    response = study_response()
    rgb = truth @ response
    rgb = rgb * (1 + rgb_noise * rng.standard_normal(rgb.shape))
    bands = np.arange(1, DEFAULT_GRID.size - 1, band_step)
    band_values = truth[..., bands] * (
        1 + band_noise * rng.standard_normal((*truth.shape[:2], bands.size))
    )
    images = [
        BandImage(image=0, band=int(band), values=band_values[..., index], sigma_px=sigma_px)
        for index, band in enumerate(bands)
    ]
    cube = spectralize(rgb, response, band_images=images)
    return BandSpectralization(
        truth,
        rgb,
        bands,
        band_values,
        cube,
        relative_error(cube, truth),
        delta_e94(cube, truth, DEFAULT_GRID),
    )
