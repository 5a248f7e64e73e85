"""Virtual dome captures and their spectralization (thesis 10.4.1-10.4.4).

A capture (:func:`simulate_capture`) renders a twin material's images
(:func:`twin.render.truth.texture_truth`) under dome LEDs, takes the RGB camera's HDR
exposure
set of every image and the spectral camera's scheduled band exposures of some images (raw frames
through :mod:`twin.dome.capture`), and converts them with the calibration of
:func:`twin.dome.setup.dome_setup` into white-balanced RGB :math:`V` and noisy band reflectance
images, the inputs of Eq. 10.12 (:func:`recon.spectralize.spectralize`).

The comparisons of 10.4.3 and 10.4.4 need the sphere-lit spectral image of Dong et al.: the
sample under all LEDs at once (:func:`sphere_lit_spectra`), bright enough that short band
exposures are nearly noise-free.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from recon.errors import InputError
from recon.metrics import delta_e94, relative_error
from recon.scheduling.dome_schedule import THESIS_RGB_EXPOSURES_S
from recon.spectralize.solve import BandImage, spectralize
from twin.dome.setup import BAND_GRID, DomeSetup
from twin.materials.textures import MATERIAL_TEXEL_REFLECTANCE, TextureTruth
from twin.render.truth import texture_truth
from twin.rigs.dome_geometry import dome_geometry

__all__ = [
    "MATERIAL_TEXEL_REFLECTANCE",
    "DomeCapture",
    "ReconstructionErrors",
    "dome_light_directions",
    "reconstruct_capture",
    "simulate_capture",
    "sphere_lit_spectra",
]


@dataclass(frozen=True)
class DomeCapture:
    """What the dome delivers for ``n`` images of one material.

    Attributes
    ----------
    truth
        ``(n, H, W, 30)`` true reflectance factors in the spectral camera's 30 bands
        (:meth:`twin.dome.capture.DomeCameras.band_reflectance`).
    rgb
        ``(n, H, W, 3)`` white-balanced HDR RGB :math:`V` per unit :math:`\\cos\\theta_i`.
    band_images
        The noisy band images, reflectance factors, with their filters (Eq. 10.1).
    spectral_exposure_s
        Summed exposure time of the band frames taken.
    """

    truth: np.ndarray
    rgb: np.ndarray
    band_images: tuple[BandImage, ...]
    spectral_exposure_s: float

    def band_values(self) -> np.ndarray:
        """The noisy band images as they are, ``(n, H, W, 30)``, NaN where a band was not taken
        (a band taken twice: its last image)."""
        values = np.full(self.truth.shape, np.nan)
        for band_image in self.band_images:
            values[band_image.image, ..., band_image.band] = band_image.values
        return values

    @property
    def rgb_exposure_s(self) -> float:
        """Summed RGB exposure time: the HDR set per image."""
        return float(self.truth.shape[0] * sum(THESIS_RGB_EXPOSURES_S))


@dataclass(frozen=True)
class ReconstructionErrors:
    """Eq. 6.8 relative error (%) and Delta E94 per pixel, ``(n, H, W)`` each, and the texels
    that show material."""

    relative_pct: np.ndarray
    delta_e94: np.ndarray
    material: np.ndarray

    @classmethod
    def of(
        cls, estimate: np.ndarray, truth: np.ndarray, shown: np.ndarray | None = None
    ) -> ReconstructionErrors:
        """The errors of ``estimate`` against ``truth``; the material texels are those of a
        truth of at least :data:`MATERIAL_TEXEL_REFLECTANCE` and, where given, ``shown``
        ``(n, H, W)`` (the texels that show the sample's surface alone,
        :func:`twin.render.truth.surface_share`)."""
        material = truth.mean(-1) >= MATERIAL_TEXEL_REFLECTANCE
        return cls(
            relative_error(estimate, truth),
            delta_e94(estimate, truth, BAND_GRID),
            material if shown is None else material & shown,
        )

    def summary(self, images: slice | Sequence[int] = slice(None)) -> dict[str, float]:
        """Means (and the median relative error, which the few near-black texels of shadows do
        not dominate, and the 95th percentile of Delta E94) over the material texels of
        ``images``."""
        material = self.material[images]
        relative, colour = self.relative_pct[images][material], self.delta_e94[images][material]
        return {
            "mean_relative_error_pct": float(relative.mean()),
            "median_relative_error_pct": float(np.median(relative)),
            "mean_delta_e94": float(colour.mean()),
            "p95_delta_e94": float(np.percentile(colour, 95)),
            "material_texel_fraction": float(material.mean()),
        }

    def group_summaries(
        self, groups: Mapping[str, Sequence[int]]
    ) -> dict[str, dict[str, float] | None]:
        """:meth:`summary` of each group of images, ``None`` for a group without a material
        texel (e.g. a camera that sees only a raised sample's sides)."""
        return {
            group: self.summary(images) if self.material[images].any() else None
            for group, images in groups.items()
        }


def dome_light_directions(setup: DomeSetup, leds: Sequence[int] | np.ndarray) -> np.ndarray:
    """Unit directions ``(n, 3)`` of dome LEDs ``leds`` (stage at 0)."""
    directions = dome_geometry(setup.cameras.config).led_directions
    indices = np.asarray(leds, int)
    if indices.min() < 0 or indices.max() >= len(directions):
        raise InputError(f"leds: expected indices in [0, {len(directions) - 1}]")
    return directions[indices]


def simulate_capture(
    setup: DomeSetup,
    truth: TextureTruth,
    light_dirs: np.ndarray,
    bands_per_image: Sequence[Sequence[int]],
    rng: np.random.Generator,
    *,
    exposure_scale: float = 1.0,
) -> DomeCapture:
    """Raw frames of every image and band, converted by the calibration (module description).

    Parameters
    ----------
    setup
        The calibrated dome.
    truth
        The images' true spectra (their ``(light, view)`` pairs rendered before).
    light_dirs
        ``(n, 3)`` the LED direction of each image (for :math:`\\cos\\theta_i`).
    bands_per_image
        For each image the band indices (0-29) the spectral camera exposes during it; empty
        for images without spectral data. A band may appear in several images.
    rng
        Source of the cameras' temporal noise.
    exposure_scale
        Factor on the planned band exposures.
    """
    n = truth.weights.shape[0]
    if len(bands_per_image) != n or np.shape(light_dirs) != (n, 3):
        raise InputError(
            f"light_dirs, bands_per_image: expected (n, 3) and n lists for {n} images, got "
            f"{np.shape(light_dirs)} and {len(bands_per_image)}"
        )
    cameras = setup.cameras
    rgb_basis, band_basis = cameras.basis_rates(truth)
    cos_i = np.asarray(light_dirs)[:, 2]
    sigma = setup.filter_sigma(exposure_scale)
    rgb, band_images, spectral_s = [], [], 0.0
    for image in range(n):
        weights = cos_i[image] * truth.weights[image]
        frames = cameras.rgb_frames(weights @ rgb_basis, np.array(THESIS_RGB_EXPOSURES_S), rng)
        rgb.append(
            setup.rgb.white_balanced(frames, cos_i[image], texel_px=cameras.pixels_per_texel)
        )
        for band in bands_per_image[image]:
            exposure = float(setup.exposures_s[band] * exposure_scale)
            frame = cameras.band_frame(weights @ band_basis[:, band], exposure, rng)
            values = setup.spectral.reflectance(
                frame,
                exposure,
                band,
                setup.led_per_band[band],
                cos_i[image],
                texel_px=cameras.pixels_per_texel,
            )
            band_images.append(BandImage(image, int(band), values, float(sigma[band])))
            spectral_s += exposure
    return DomeCapture(
        cameras.band_reflectance(truth), np.stack(rgb), tuple(band_images), spectral_s
    )


def reconstruct_capture(setup: DomeSetup, capture: DomeCapture, **options) -> np.ndarray:
    """Eq. 10.12 on a capture: the spectral cube ``(n, H, W, 30)``; ``options`` go to
    :func:`recon.spectralize.spectralize` (``p_dyn``, ``weights``, ``tol``, ...)."""
    return spectralize(capture.rgb, setup.response, band_images=capture.band_images, **options)


def sphere_lit_spectra(
    setup: DomeSetup,
    material: str,
    view_dir: np.ndarray,
    rng: np.random.Generator,
    *,
    texels: int,
    leds: Sequence[int],
) -> np.ndarray:
    """The spectral camera's image ``(H, W, 30)`` of ``material`` under all LEDs at once
    (thesis 10.4.3), as reflectance factors.

    The sum over the dome's 198 LEDs is estimated from the LEDs ``leds`` (rendered one by one),
    scaled to 198; with that much light band exposures at half the full well (or the planned
    ones, if shorter) are nearly noise-free.
    """
    lights = dome_light_directions(setup, leds)
    truth = texture_truth(
        material, lights, np.repeat(np.asarray(view_dir)[None], len(lights), 0), texels=texels
    )
    _, band_basis = setup.cameras.basis_rates(truth)
    scale = setup.cameras.config.led_count / len(lights)
    rates = scale * np.einsum("n,nhwp,pb->hwb", lights[:, 2], truth.weights, band_basis)
    irradiance = scale * lights[:, 2].sum()
    bands = []
    full_well = setup.cameras.spectral.saturation_capacity_e
    for band, planned in enumerate(setup.exposures_s):
        exposure = min(float(planned), 0.5 * full_well / float(rates[..., band].max()))
        frame = setup.cameras.band_frame(rates[..., band], float(exposure), rng)
        bands.append(
            setup.spectral.reflectance(
                frame,
                float(exposure),
                band,
                setup.led_per_band[band],
                irradiance,
                texel_px=setup.cameras.pixels_per_texel,
            )
        )
    return np.stack(bands, axis=-1)
