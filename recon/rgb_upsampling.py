"""Reflectance spectra from an sRGB image: colour's Jakob 2019 model or the project's
spectralization from a few known spectra.

An sRGB-encoded image (PNG, JPEG or TIFF, 8 or 16 bit) is read as a reflectance image: its
decoded, linear values are the linear sRGB of the surface under CIE D65, a perfect white
giving 1. Two named methods turn it into spectra on :data:`recon.spectra.DEFAULT_GRID`:

- ``"jakob2019"``: each texel's spectrum is the smooth sigmoid-of-a-quadratic of Jakob and
  Hanika (2019) that has its colour, read from a coefficient table for sRGB (shipped with
  spectwin: ``recon/data/spectra/jakob2019_srgb_16.coeff``, made with colour's
  ``LUT3D_Jakob2019``). Needs no measurement; metamers of the image's colours are not resolved.
- ``"spectralization"``: the thesis's Eq. 6.10 (:func:`recon.spectralize.spectralize`) with the
  image as the camera and a few spectra measured on the sample (a spectrophotometer) at known
  pixels; their spectra spread along the image's appearance graph.

References
----------
- Jakob, W., Hanika, J. (2019). A Low-Dimensional Function Space for Efficient Spectral
  Upsampling. Computer Graphics Forum 38(2).
- IEC 61966-2-1:1999 (sRGB); colour-science's ``LUT3D_Jakob2019``, ``cctf_decoding``,
  ``XYZ_to_RGB``.
"""

from __future__ import annotations

from functools import cache
from io import BytesIO
from pathlib import Path
from typing import Literal

import colour
import numpy as np
from colour.recovery import LUT3D_Jakob2019

from recon.errors import InputError
from recon.measured_data import data_path
from recon.spectra import DEFAULT_GRID, SampledSpectra, from_colour, resample

__all__ = [
    "UPSAMPLING_METHODS",
    "read_srgb_image",
    "reduce_image",
    "srgb_response",
    "upsample_srgb",
]

UPSAMPLING_METHODS = ("jakob2019", "spectralization")
"""The named ways from sRGB to spectra (module docstring)."""

_JAKOB_TABLE = "spectra/jakob2019_srgb_16.coeff"
_COVERED_NM = (400.0, 700.0)  # known spectra must cover these; beyond, they are held constant


def read_srgb_image(path: str | Path, data: bytes | None = None) -> np.ndarray:
    """Linear sRGB ``(H, W, 3)`` of an 8- or 16-bit sRGB-encoded image file, in [0, 1];
    ``data``: the file's bytes when they come from elsewhere (an archive), ``path`` then names it
    in errors."""
    from skimage import io

    path = Path(path)
    if data is None and not path.is_file():
        raise InputError(f"{path}: no such image file; expected a PNG, JPEG or TIFF")
    try:
        pixels = io.imread(path if data is None else BytesIO(data))
    except (OSError, ValueError) as error:
        raise InputError(f"{path}: not a readable image ({error})") from None
    if pixels.ndim != 3 or pixels.shape[2] not in (3, 4) or pixels.dtype.kind != "u":
        raise InputError(
            f"{path}: expected an 8- or 16-bit RGB image, got {pixels.dtype} of shape "
            f"{pixels.shape}"
        )
    encoded = pixels[..., :3] / np.iinfo(pixels.dtype).max
    return np.clip(colour.cctf_decoding(encoded, function="sRGB"), 0.0, 1.0)


def reduce_image(linear: np.ndarray, max_side: int) -> tuple[np.ndarray, int]:
    """``linear`` reduced by area averaging (``skimage.transform.downscale_local_mean``) by
    the smallest whole factor that brings its longer side to at most ``max_side``; returns the
    image and the factor (1: unchanged)."""
    from skimage import transform

    factor = max(1, int(np.ceil(max(linear.shape[:2]) / max_side)))
    if factor == 1:
        return linear, 1
    return transform.downscale_local_mean(linear, (factor, factor, 1)), factor


def srgb_response() -> np.ndarray:
    """``(33, 3)`` the response of "an sRGB camera" on ``DEFAULT_GRID``: reflectance spectra
    times CIE D65, integrated against the CIE 1931 2 degree observer and turned into linear sRGB,
    scaled so that a perfect white gives (1, 1, 1) (up to the grid's quadrature)."""
    observer = from_colour(colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"])
    cmfs = resample(observer, DEFAULT_GRID).values.T  # (K, 3)
    light = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID).values
    to_xyz = cmfs * (light * DEFAULT_GRID.quadrature_weights())[:, None]
    white = np.ones(DEFAULT_GRID.size) @ to_xyz
    to_rgb = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    response = (to_xyz / white[1]) @ to_rgb.T
    return response / (np.ones(DEFAULT_GRID.size) @ response)


@cache
def _jakob_table() -> LUT3D_Jakob2019:
    table = LUT3D_Jakob2019()
    table.read(str(data_path(_JAKOB_TABLE)))
    return table


def _jakob2019(linear: np.ndarray) -> np.ndarray:
    """Jakob 2019 spectra of linear sRGB values ``(..., 3)`` on ``DEFAULT_GRID``; a colour
    brighter than 1 in some channel is upsampled scaled into the table's range, and its spectrum
    scaled back (a highlight of a BTF)."""
    colours = np.maximum(linear.reshape(-1, 3), 0.0)
    brightness = np.maximum(colours.max(axis=1, keepdims=True), 1.0)
    coefficients = _jakob_table().RGB_to_coefficients(colours / brightness)
    wavelengths = DEFAULT_GRID.wavelengths_nm
    quadratic = (
        coefficients[:, :1] * wavelengths**2
        + coefficients[:, 1:2] * wavelengths
        + coefficients[:, 2:]
    )
    spectra = brightness * (0.5 + quadratic / (2 * np.sqrt(1 + quadratic**2)))
    return spectra.reshape(*linear.shape[:-1], DEFAULT_GRID.size)


def upsample_srgb(
    linear: np.ndarray,
    method: Literal["jakob2019", "spectralization"],
    *,
    known_pixels: np.ndarray | None = None,
    known_spectra: SampledSpectra | None = None,
) -> SampledSpectra:
    """Reflectance spectra ``(H, W, 33)`` on ``DEFAULT_GRID`` of a linear sRGB image.

    Parameters
    ----------
    linear
        ``(H, W, 3)`` linear sRGB reflectance image (:func:`read_srgb_image`).
    method
        One of :data:`UPSAMPLING_METHODS` (module docstring).
    known_pixels
        ``(m, 2)`` (row, column) of the measured spectra (``"spectralization"`` only).
    known_spectra
        ``(m, K)`` the spectra measured there, on any grid covering 400-700 nm (held constant
        beyond its ends).

    Returns
    -------
    SampledSpectra
        Reflectances: in [0, 1] from the spectralization (clipped); from Jakob 2019 in [0, 1]
        for colours within [0, 1], above for brighter ones.
    """
    if method not in UPSAMPLING_METHODS:
        raise InputError(f"method: expected one of {', '.join(UPSAMPLING_METHODS)}, got {method!r}")
    if method == "jakob2019":
        return SampledSpectra(DEFAULT_GRID, _jakob2019(linear))
    return SampledSpectra(
        DEFAULT_GRID, np.clip(_spectralized(linear, known_pixels, known_spectra), 0.0, 1.0)
    )


def _spectralized(
    linear: np.ndarray, known_pixels: np.ndarray | None, known_spectra: SampledSpectra | None
) -> np.ndarray:
    from recon.spectralize import spectralize

    if known_pixels is None or known_spectra is None:
        raise InputError(
            "known spectra: spectralization needs spectra measured at known pixels of the image"
        )
    pixels = np.asarray(known_pixels, int).reshape(-1, 2)
    height, width = linear.shape[:2]
    inside = (pixels >= 0).all(axis=1) & (pixels[:, 0] < height) & (pixels[:, 1] < width)
    if not inside.all():
        raise InputError(
            f"known pixels: {pixels[~inside].tolist()} lie outside the {height} x {width} image"
        )
    spectra = np.atleast_2d(known_spectra.values)
    if len(spectra) != len(pixels):
        raise InputError(
            f"known spectra: {len(spectra)} spectra for {len(pixels)} known pixels; expected one "
            "spectrum per pixel"
        )
    covered = known_spectra.grid.wavelengths_nm
    if covered[0] > _COVERED_NM[0] or covered[-1] < _COVERED_NM[1]:
        raise InputError(
            f"known spectra: cover {covered[0]:g}-{covered[-1]:g} nm; expected at least "
            f"{_COVERED_NM[0]:g}-{_COVERED_NM[1]:g} nm"
        )
    on_grid = resample(
        SampledSpectra(known_spectra.grid, spectra), DEFAULT_GRID, out_of_range="clamp"
    ).values
    return spectralize(
        linear,
        srgb_response(),
        known_pixels=pixels[:, 0] * width + pixels[:, 1],
        known_spectra=on_grid,
    )
