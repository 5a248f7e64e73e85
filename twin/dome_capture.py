"""Raw frames of the LED dome's cameras for twin textures (thesis 10.4, Eq. 10.9-10.11).

The thesis simulates its RGB-spectral dome from spectral reference images :math:`S_{ref}`: the
RGB cameras' exposure series :math:`M_{RGB}(C S_{ref}(p)\\,\\mathrm{diag}(L), t_i)` (Eq. 10.10)
and one spectral-camera exposure per band :math:`M_{spectral}(S_{ref}(p)\\,\\mathrm{diag}(L),
t_\\lambda)` (Eq. 10.11), with :math:`M` the camera model of Eq. 10.9. Here :math:`S_{ref}` is
a :class:`twin.texture_truth.TextureTruth` (weights of part spectra per texel), :math:`L` the
dome's phosphor-white LED at the dome radius, and :math:`M` the twin's sensor model
(:class:`twin.sensor.Sensor`: shot and read noise, dark current and its non-uniformity, PRNU, the
OECF and the ADC), which is more detailed than Eq. 10.9's single Gaussian.

Geometry: texel ``(row, column)`` is one pixel of the spectral camera (the CoolSNAP K4 behind
the VariSpec) and one Bayer quad of the RGB camera (SVS-Vistek 4022), i.e. the images are
registered, as the thesis assumes for its simulation. A texel lit from polar angle
:math:`\\theta_i` receives the LED's irradiance :math:`I(\\lambda) \\cos\\theta_i / r^2` and
sends the radiance :math:`\\rho\\, I \\cos\\theta_i / (\\pi r^2)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from recon.spectra import SampledSpectra
from twin.components import FINE_GRID, LiquidCrystalTunableFilter, PhosphorWhiteLED
from twin.components.targets import zenith_white_reflectance
from twin.rig_config import DomeConfig, load_rig
from twin.sensor import Sensor
from twin.texture_truth import TextureTruth

__all__ = ["THESIS_BANDS_NM", "DomeCameras", "dome_cameras"]

THESIS_BANDS_NM = np.arange(410.0, 701.0, 10.0)
"""The spectral camera's 30 bands, 410-700 nm in 10 nm steps (thesis 10.4.1)."""


@dataclass(frozen=True)
class DomeCameras:
    """The dome's RGB and spectral cameras, its LCTF bands and LED, sized for ``texels``.

    Attributes
    ----------
    config
        The dome rig.
    rgb
        The RGB camera, a ``2 texels`` square window (one Bayer quad per texel).
    spectral
        The monochrome camera behind the LCTF, a ``texels`` square window.
    bands
        ``(30, len(FINE_GRID))`` LCTF transmission per band.
    led
        The LED's intensity on ``FINE_GRID``, W sr^-1 nm^-1.
    """

    config: DomeConfig
    rgb: Sensor
    spectral: Sensor
    bands: SampledSpectra
    led: SampledSpectra

    def _radiance(self, reflectance: np.ndarray) -> SampledSpectra:
        """Radiance of reflectance factors ``(..., len(FINE_GRID))`` facing the LED."""
        return SampledSpectra(
            FINE_GRID, reflectance * self.led.values / (math.pi * self.config.radius_m**2)
        )

    def basis_rates(self, truth: TextureTruth) -> tuple[np.ndarray, np.ndarray]:
        """Photo-electrons per second per unit weight of each basis spectrum facing the LED:
        RGB ``(n_basis, 3)`` and spectral bands ``(n_basis, 30)``."""
        radiance = self._radiance(truth.fine_basis)
        return self.rgb.mean_electrons(radiance), self.spectral.mean_electrons(
            radiance, self.bands
        )

    def white_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """Rates of the white reference (Zenith) facing the LED: RGB ``(3,)``, bands ``(30,)``."""
        radiance = self._radiance(zenith_white_reflectance(FINE_GRID).values)
        return self.rgb.mean_electrons(radiance), self.spectral.mean_electrons(
            radiance, self.bands
        )

    def rgb_frames(
        self,
        rates_e_per_s: np.ndarray,
        exposures_s: np.ndarray,
        rng: np.random.Generator,
    ) -> np.ndarray:
        """Bayer raw frames ``(n_exposures, 2H, 2W)`` of an RGB rate image ``(H, W, 3)``."""
        quads = np.repeat(np.repeat(rates_e_per_s, 2, axis=0), 2, axis=1)
        return np.stack(
            [self.rgb.capture(quads * float(t), float(t), rng) for t in np.atleast_1d(exposures_s)]
        )

    def band_frame(
        self, rates_e_per_s: np.ndarray, exposure_s: float, rng: np.random.Generator
    ) -> np.ndarray:
        """One raw spectral-camera frame ``(H, W)`` of a band's rate image ``(H, W)``."""
        return self.spectral.capture(rates_e_per_s * float(exposure_s), float(exposure_s), rng)

    def dark_frames(
        self, exposures_s: np.ndarray, count: int, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """``count`` spectral-camera dark frames per exposure time (thesis 10.3: 200), stacked
        ``(n, H, W)``, with their exposure times ``(n,)``."""
        times = np.repeat(np.asarray(exposures_s, np.float64), count)
        return np.stack([self.spectral.dark_frame(float(t), rng) for t in times]), times


def dome_cameras(
    texels: int, *, config: DomeConfig | None = None, bands_nm: np.ndarray = THESIS_BANDS_NM
) -> DomeCameras:
    """The dome's cameras for ``texels`` square images (``scenes/rigs/dome.yaml`` by default)."""
    config = config if config is not None else load_rig("dome")
    lctf = LiquidCrystalTunableFilter.varispec(
        config.spectral_camera.filter, band_centres_nm=tuple(bands_nm)
    )
    return DomeCameras(
        config,
        Sensor(config.rgb_camera, roi=(2 * texels, 2 * texels)),
        Sensor(config.spectral_camera.definition, roi=(texels, texels)),
        lctf.transmission(FINE_GRID),
        PhosphorWhiteLED().intensity(FINE_GRID),
    )
