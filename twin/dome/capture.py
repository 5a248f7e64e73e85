"""Raw frames of the LED dome's cameras for twin textures (thesis 10.4, Eq. 10.9-10.11).

The thesis simulates its RGB-spectral dome from spectral reference images :math:`S_{ref}`: the
RGB cameras' exposure series :math:`M_{RGB}(C S_{ref}(p)\\,\\mathrm{diag}(L), t_i)` (Eq. 10.10)
and one spectral-camera exposure per band :math:`M_{spectral}(S_{ref}(p)\\,\\mathrm{diag}(L),
t_\\lambda)` (Eq. 10.11), with :math:`M` the camera model of Eq. 10.9. Here :math:`S_{ref}` is
a :class:`twin.materials.textures.TextureTruth` (weights of part spectra per texel), :math:`L` the
dome's phosphor-white LED at the dome radius, and :math:`M` the twin's sensor model
(:class:`twin.sensor.model.Sensor`: shot and read noise, dark current and its non-uniformity, PRNU,
the
OECF and the ADC), which is more detailed than Eq. 10.9's single Gaussian.

Geometry: both cameras have 2048 x 2048 pixels over the dome's 0.2 m field, 0.098 mm per pixel,
so a texel of a 4 cm sample at 48 texels spans about 8 x 8 pixels of the spectral camera (the
CoolSNAP K4 behind the VariSpec) and 4 x 4 Bayer quads of the RGB camera (SVS-Vistek 4022)
(:func:`pixels_per_texel`). The frames are taken at that resolution and the processing averages
each texel's pixels (:mod:`recon.calibration.dome`). The images are registered, as the thesis
assumes for its simulation. A texel lit from polar angle
:math:`\\theta_i` receives the LED's irradiance :math:`I(\\lambda) \\cos\\theta_i / r^2` and
sends the radiance :math:`\\rho\\, I \\cos\\theta_i / (\\pi r^2)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from recon.errors import InputError
from recon.radiometric.dark_frames import average_dark_frames
from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import zenith_white_reflectance
from twin.materials.textures import TextureTruth
from twin.rigs.rig_config import DomeConfig, load_rig
from twin.sensor.model import Sensor

__all__ = ["THESIS_BANDS_NM", "DomeCameras", "dome_cameras", "pixels_per_texel"]

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
        The RGB camera, a ``texels x pixels_per_texel`` square window.
    spectral
        The monochrome camera behind the LCTF, the same window.
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
    pixels_per_texel: int

    def _pixels(self, texel_image: np.ndarray) -> np.ndarray:
        """A texel image ``(H, W, ...)`` repeated onto the camera pixels."""
        block = self.pixels_per_texel
        return np.repeat(np.repeat(texel_image, block, axis=0), block, axis=1)

    def _radiance(self, reflectance: np.ndarray) -> SampledSpectra:
        """Radiance of reflectance factors ``(..., len(FINE_GRID))`` facing the LED."""
        return SampledSpectra(
            FINE_GRID, reflectance * self.led.values / (math.pi * self.config.radius_m**2)
        )

    def basis_rates(self, truth: TextureTruth) -> tuple[np.ndarray, np.ndarray]:
        """Photo-electrons per second per unit weight of each basis spectrum facing the LED:
        RGB ``(n_basis, 3)`` and spectral bands ``(n_basis, 30)``."""
        radiance = self._radiance(truth.fine_basis)
        return self.rgb.mean_electrons(radiance), self.spectral.mean_electrons(radiance, self.bands)

    def band_reflectance(self, truth: TextureTruth) -> np.ndarray:
        """True reflectance factors ``(n, H, W, 30)`` as the spectral camera defines its bands:
        each band the reflectance averaged with the weight LCTF x QE x LED (out-of-band leakage
        included; at 410 nm it lifts a red Lego brick's value by half), the weighting the gonio
        evaluation uses too (:mod:`twin.validate.gonio_evaluation`)."""
        weights = self.spectral.electron_responses(FINE_GRID, self.bands).values * self.led.values
        weights /= weights.sum(1, keepdims=True)
        return truth.weights @ (truth.fine_basis @ weights.T)

    def white_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """Rates of the white reference (Zenith) facing the LED: RGB ``(3,)``, bands ``(30,)``."""
        radiance = self._radiance(zenith_white_reflectance(FINE_GRID).values)
        return self.rgb.mean_electrons(radiance), self.spectral.mean_electrons(radiance, self.bands)

    def rgb_frames(
        self,
        rates_e_per_s: np.ndarray,
        exposures_s: np.ndarray,
        rng: np.random.Generator,
    ) -> np.ndarray:
        """Bayer raw frames ``(n_exposures, bH, bW)`` of an RGB rate image ``(H, W, 3)`` per
        texel, ``b`` pixels per texel."""
        quads = self._pixels(rates_e_per_s)
        return np.stack(
            [self.rgb.capture(quads * float(t), float(t), rng) for t in np.atleast_1d(exposures_s)]
        )

    def band_frame(
        self, rates_e_per_s: np.ndarray, exposure_s: float, rng: np.random.Generator
    ) -> np.ndarray:
        """One raw spectral-camera frame ``(bH, bW)`` of a band's rate image ``(H, W)`` per
        texel."""
        electrons = self._pixels(rates_e_per_s * float(exposure_s))
        return self.spectral.capture(electrons, float(exposure_s), rng)

    def dark_frames(
        self, exposures_s: np.ndarray, count: int, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """``count`` spectral-camera dark frames at each exposure time (thesis 10.3: 200),
        averaged per time: ``(n_times,)`` times and ``(n_times, bH, bW)`` mean frames
        (:func:`recon.radiometric.dark_frames.average_dark_frames`, one time at a time to bound
        memory)."""
        times = np.asarray(exposures_s, np.float64)
        means = [
            average_dark_frames(
                np.stack([self.spectral.dark_frame(float(t), rng) for _ in range(count)]),
                np.full(count, t),
            )[1][0]
            for t in times
        ]
        return times, np.stack(means)


def pixels_per_texel(config: DomeConfig, sample_size_m: float, texels: int) -> int:
    """Spectral-camera pixels across one texel of a ``sample_size_m`` texture of ``texels``
    texels, rounded to an even count of at least 2 (whole Bayer quads on the RGB camera)."""
    sensor = Sensor(config.spectral_camera.definition)
    pitch_m = config.spectral_camera.field_of_view_m / sensor.width
    return max(2, 2 * round(sample_size_m / texels / pitch_m / 2))


def dome_cameras(
    texels: int,
    *,
    sample_size_m: float = 0.04,
    config: DomeConfig | None = None,
    bands_nm: np.ndarray = THESIS_BANDS_NM,
    texel_px: int | None = None,
) -> DomeCameras:
    """The dome's cameras for ``texels`` square images of a ``sample_size_m`` sample
    (``scenes/rigs/dome.yaml`` by default).

    ``texel_px`` replaces the pixels per texel that the sample size gives: 2 images each texel
    with one Bayer quad of the RGB camera and 2 x 2 spectral-camera pixels, the per-pixel regime
    in which the thesis evaluates real captures (10.5, Fig. 10.24: pixel spectra).
    """
    config = config if config is not None else load_rig("dome")
    if texel_px is not None and (texel_px < 2 or texel_px % 2):
        raise InputError(
            f"texel_px: expected an even number of pixels per texel, at least 2 (whole Bayer "
            f"quads), got {texel_px}"
        )
    block = texel_px if texel_px is not None else pixels_per_texel(config, sample_size_m, texels)
    lctf = LiquidCrystalTunableFilter.varispec(
        config.spectral_camera.filter, band_centres_nm=tuple(bands_nm)
    )
    return DomeCameras(
        config,
        Sensor(config.rgb_camera, roi=(block * texels, block * texels)),
        Sensor(config.spectral_camera.definition, roi=(block * texels, block * texels)),
        lctf.transmission(FINE_GRID),
        PhosphorWhiteLED().intensity(FINE_GRID),
        block,
    )
