"""Test images made of real spectra under real cameras, for the chapter 7 protocols.

Every case is a spectral image with the camera that photographs it:

- ``llanos2019``: Llanos's real seven-band image of a ColorChecker with its own camera
  (:func:`recon.measured_data.read_llanos2019_multispectral`);
- for each real reflectance set that ships with spectwin (``recon/data/spectra/reflectances``:
  VHREL clothes and food, DuPont paint chips, the 190 rawtoaces training spectra, the Esser and
  Macbeth charts) a Voronoi **mosaic** (:func:`~recon.experiments.synthetic_images.material_mosaic`,
  shading 0.6-1.0) and a **smooth blend**
  (:func:`~recon.experiments.synthetic_images.smooth_blend`, shading 0.8-1.2), each under CIE
  D65 and the measured sensitivities of a different one of the 51 rawtoaces cameras (every
  fourth by name).

Reflectances are resampled to the thesis's 400-720 nm, 10 nm grid (sets that end at 700 nm keep
their last value up to 720 nm). Each camera-times-light response is scaled so that a perfect white
gives 1 in its largest channel.

:func:`holder_bar_case` turns the clothes mosaic into a noisy band-image capture with a black
holder bar across it, the case where Eq. 10.2's dynamic-range compression meets black pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from recon.errors import InputError
from recon.experiments.sampling import add_rgb_noise
from recon.experiments.synthetic_images import material_mosaic, smooth_blend
from recon.measured_data import (
    camera_names,
    read_camera_sensitivities,
    read_llanos2019_multispectral,
    read_spectra_csv,
)
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, from_colour, resample
from recon.spectralize.solve import BandImage

__all__ = [
    "REFLECTANCE_SETS",
    "HolderBarCase",
    "RealTestImage",
    "daylight_response",
    "holder_bar_case",
    "real_test_image",
    "real_test_image_names",
]

REFLECTANCE_SETS = (
    "vhrel_clothes",
    "vhrel_food",
    "dupont_paint_chips",
    "rawtoaces_training_190",
    "esser_chart",
    "macbeth_colorchecker",
)
"""The real reflectance sets (file stems in ``recon/data/spectra/reflectances``)."""

_KINDS = ("mosaic", "blend")


@dataclass(frozen=True)
class RealTestImage:
    """A test case: ``truth`` ``(H, W, K)`` spectra on ``grid``, ``response`` ``(K, 3)`` with
    ``rgb = truth @ response`` (Eq. 7.1, band integrals), and what they are made of."""

    name: str
    truth: np.ndarray
    response: np.ndarray
    camera: str
    description: str
    grid: WavelengthGrid = DEFAULT_GRID

    def response_per_nm(self) -> SampledSpectra:
        """The response as a camera's response file gives it: ``(3, K)`` rows R, G, B per
        nanometre (the band integrals divided by the grid's quadrature weights)."""
        per_nm = self.response / self.grid.quadrature_weights()[:, None]
        return SampledSpectra(self.grid, per_nm.T, ("R", "G", "B"))


def real_test_image_names() -> tuple[str, ...]:
    """``"llanos2019"`` and ``"<set> <kind>"`` for every reflectance set and kind."""
    return ("llanos2019", *(f"{name} {kind}" for name in REFLECTANCE_SETS for kind in _KINDS))


def _camera_for(index: int) -> str:
    cameras = camera_names()
    return cameras[(4 * index) % len(cameras)]


def daylight_response(camera: str) -> np.ndarray:
    """``(33, 3)``: the camera's measured sensitivities times CIE D65 on the default grid,
    scaled so that a perfect white gives 1 in the largest channel."""
    sensitivities = resample(read_camera_sensitivities(camera), DEFAULT_GRID).values.T
    light = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID).values
    response = sensitivities * light[:, None]
    return response / (np.ones(DEFAULT_GRID.size) @ response).max()


def real_test_image(name: str, *, side: int = 192, seed: int = 0) -> RealTestImage:
    """The test case ``name`` (one of :func:`real_test_image_names`).

    Parameters
    ----------
    name
        ``"llanos2019"`` (its own size, 342 x 408 px, seven bands) or ``"<set> <kind>"``.
    side
        Height and width of the mosaics and blends, pixels.
    seed
        Seed of the mosaic cells and the blend centres.
    """
    names = real_test_image_names()
    if name not in names:
        raise InputError(f"test image {name!r}: expected one of {', '.join(names)}")
    if name == "llanos2019":
        real = read_llanos2019_multispectral()
        return RealTestImage(
            name, real.image, real.response, "Llanos 2019 sensor", "real 7-band image", real.grid
        )
    set_name, kind = name.split(" ")
    reflectances = read_spectra_csv(f"spectra/reflectances/{set_name}.csv")
    values = np.clip(resample(reflectances, DEFAULT_GRID, out_of_range="clamp").values, 0, None)
    camera = _camera_for(names.index(name) - 1)
    if kind == "mosaic":
        cells = max(60, values.shape[0])
        truth, _ = material_mosaic(values, (side, side), cells=cells, seed=seed)
        description = f"{values.shape[0]} spectra in {cells} Voronoi cells, shading 0.6-1.0"
    else:
        truth = smooth_blend(values, (side, side), seed=seed)
        description = f"smooth blend of 12 of {values.shape[0]} spectra, shading 0.8-1.2"
    return RealTestImage(name, truth, daylight_response(camera), camera, description)


@dataclass(frozen=True)
class HolderBarCase:
    """A band-image capture (Eq. 10.1) of the clothes mosaic with a black holder bar across it:
    ``truth`` ``(side, side, 33)`` (zero on the bar), noisy ``rgb`` and ``band_images`` (every
    fourth band, filtered at ``sigma_px``), the masks of the ``bar`` and of the lit pixels
    ``beside`` it (within a fifth of the side of its centre line)."""

    truth: np.ndarray
    rgb: np.ndarray
    response: np.ndarray
    band_images: tuple[BandImage, ...]
    bar: np.ndarray
    beside: np.ndarray


def holder_bar_case(
    side: int = 96,
    *,
    rgb_noise: float = 0.01,
    band_noise: float = 0.05,
    sigma_px: float = 2.0,
    seed: int = 0,
) -> HolderBarCase:
    """The case where Eq. 10.2's scale meets black pixels: Gaussian noise of ``rgb_noise`` of
    the mean RGB and ``band_noise`` of each band's mean (the same on the bar, as a dark frame's
    read noise is)."""
    case = real_test_image("vhrel_clothes mosaic", side=side, seed=seed)
    rows = np.arange(side)[:, None] * np.ones((1, side))
    centre = 0.48 * side
    bar = np.abs(rows - centre) < 0.07 * side
    truth = np.where(bar[..., None], 0.0, case.truth)
    rng = np.random.default_rng(seed)
    rgb = add_rgb_noise(truth @ case.response, rgb_noise, rng)
    bands = tuple(
        BandImage(
            0,
            b,
            truth[..., b] + rng.normal(0, band_noise * truth[..., b].mean(), rows.shape),
            sigma_px,
        )
        for b in range(0, truth.shape[-1], 4)
    )
    beside = ~bar & (np.abs(rows - centre) < 0.2 * side)
    return HolderBarCase(truth, rgb, case.response, bands, bar, beside)
