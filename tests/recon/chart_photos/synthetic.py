"""Photographs of a ColorChecker made from measurements, for the tests of ``spectwin camchar``.

A camera whose measured sensitivities are *not* among the 51 cameras the default prior is
learned from (isetbio's Nikon D100, ``recon/data/spectra/sensors``) photographs the ColorChecker
of isetbio's measurement under a CIE illuminant: each patch's device RGB is the patches'
reflectance times the light times the sensitivities (Eq. 9.4) on 5 nm, drawn as a quadrilateral
at 84 % of its cell between the chart's corners, on a dark surround, with Gaussian noise, and
written as a 16-bit RGB TIFF, a 16-bit PNG, a single-channel RGGB mosaic TIFF or a DNG (a camera
raw file LibRaw reads: RGGB, black level, white level).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import tifffile
from skimage import draw

from recon.chart_photos.charts import named_chart
from recon.chart_photos.lights import light_spectrum
from recon.chart_photos.patches import chart_homography
from recon.measured_data import read_spectra_csv
from recon.spectra import SampledSpectra, WavelengthGrid, resample

CAMERA = "spectra/sensors/nikon_d100_rgb.csv"
SHAPE = (600, 900)
CORNERS = np.array([[150.0, 120.0], [760.0, 150.0], [740.0, 540.0], [130.0, 500.0]])
CORNERS_TEXT = "150,120;760,150;740,540;130,500"
BLACK_LEVEL = 512
WHITE_LEVEL = 16383


def camera_truth() -> SampledSpectra:
    """The Nikon D100's measured sensitivities (isetbio), rows R, G, B, 380-1068 nm."""
    return read_spectra_csv(CAMERA)


def patch_rgb(light: str, peak: float) -> np.ndarray:
    """``(24, 3)`` device RGB of the chart's patches under ``light``, largest value ``peak``."""
    grid = WavelengthGrid.regular(380, 780, 5)
    reflectances = resample(named_chart("colorchecker").reflectances, grid).values
    spectrum = resample(light_spectrum(light), grid).values[0]
    rgb = (reflectances * spectrum) @ resample(camera_truth(), grid).values.T
    return rgb / rgb.max() * peak


def rgb_image(light: str = "D65", *, peak: float = 40000.0, seed: int = 0) -> np.ndarray:
    """``(H, W, 3)`` float linear photograph of the chart (module description)."""
    image = np.full((*SHAPE, 3), 0.01 * peak)
    homography = chart_homography(CORNERS, 4, 6)
    rgb = patch_rgb(light, peak)
    for patch in range(24):
        row, column = divmod(patch, 6)
        cell = np.array([[0.08, 0.08], [0.92, 0.08], [0.92, 0.92], [0.08, 0.92]]) + [column, row]
        mapped = np.column_stack([cell, np.ones(4)]) @ homography.T
        corners = mapped[:, :2] / mapped[:, 2:]
        image[draw.polygon2mask(SHAPE, corners[:, ::-1])] = rgb[patch]
    noise = np.random.default_rng(seed).normal(0.0, 0.001 * peak, image.shape)
    return image + noise


def mosaic(image: np.ndarray) -> np.ndarray:
    """The RGGB mosaic ``(H, W)`` of an RGB image."""
    out = image[:, :, 1].copy()
    out[0::2, 0::2] = image[0::2, 0::2, 0]
    out[1::2, 1::2] = image[1::2, 1::2, 2]
    return out


def write_tiff(path: Path, image: np.ndarray, dtype=np.uint16) -> Path:
    top = np.iinfo(dtype).max
    tifffile.imwrite(path, np.clip(np.round(image), 0, top).astype(dtype))
    return path


def write_dng(path: Path, light: str = "D65", *, seed: int = 0) -> Path:
    """A DNG of the chart's RGGB mosaic: 14-bit values over a black level of 512."""
    values = mosaic(rgb_image(light, peak=12000.0, seed=seed)) + BLACK_LEVEL
    raw = np.clip(np.round(values), 0, WHITE_LEVEL).astype(np.uint16)
    tags = [
        (50706, "B", 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, "B", 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, "s", 0, "spectwin test camera", True),  # UniqueCameraModel
        (33421, "H", 2, (2, 2), True),  # CFARepeatPatternDim
        (33422, "B", 4, (0, 1, 1, 2), True),  # CFAPattern: RGGB
        (50710, "B", 3, (0, 1, 2), True),  # CFAPlaneColor
        (50711, "H", 1, 1, True),  # CFALayout
        (50714, "H", 1, BLACK_LEVEL, True),  # BlackLevel
        (50717, "H", 1, WHITE_LEVEL, True),  # WhiteLevel
        (50721, "2i", 9, (1, 1, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1, 1, 1), True),
    ]
    tifffile.imwrite(path, raw, photometric=32803, extratags=tags, subfiletype=0)
    return path


def write_truth(path: Path) -> Path:
    """The camera's measured response as ``wavelength_nm,R,G,B`` (380-780 nm)."""
    truth = camera_truth()
    keep = truth.wavelengths_nm <= 780
    rows = [
        f"{w:g},{r:.6g},{g:.6g},{b:.6g}"
        for w, (r, g, b) in zip(truth.wavelengths_nm[keep], truth.values[:, keep].T, strict=True)
    ]
    path.write_text("wavelength_nm,R,G,B\n" + "\n".join(rows) + "\n")
    return path
