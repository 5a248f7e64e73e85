"""Spectral images as OpenEXR files in the layout of Fichet, Pacanowski and Wilkie (2021).

One channel per wavelength: emissive images use the Stokes component ``S0`` and channels named
``S0.<wavelength>nm``; reflective images (reflectance, transmittance) use ``T.<wavelength>nm``.
The wavelength is written with a comma as decimal separator (``S0.412,5nm``), as the layout
prescribes, and the header carries ``spectralLayoutVersion`` = ``"1.0"`` and, for emissive
images, ``emissiveUnits`` (``"W.m^-2.sr^-1"`` for radiance). Files are written to a temporary
name and renamed, so a failed write never leaves a file that looks complete.

References
----------
- Fichet, A., Pacanowski, R., & Wilkie, A. (2021). An OpenEXR Layout for Spectral Images.
  Journal of Computer Graphics Techniques, 10(3), 1-18. http://jcgt.org/published/0010/03/01/
"""

from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import OpenEXR

from recon.errors import InputError, MissingDataError
from recon.spectra import WavelengthGrid

__all__ = ["SpectralImage", "channel_name", "read_spectral_exr", "write_spectral_exr"]

ImageKind = Literal["emissive", "reflective"]
_COMPONENT = {"emissive": "S0", "reflective": "T"}
_CHANNEL_PATTERN = re.compile(r"^(S0|T)\.(\d+(?:,\d*)?)nm$")
_PIXEL_TYPES = {np.dtype(np.float32), np.dtype(np.float16)}


@dataclass(frozen=True, eq=False)
class SpectralImage:
    """A spectral image read from or written to EXR: ``cube`` ``(H, W, K)`` on ``grid``."""

    cube: np.ndarray
    grid: WavelengthGrid
    kind: ImageKind
    attributes: dict[str, object]


def channel_name(wavelength_nm: float, kind: ImageKind) -> str:
    """Channel name of one wavelength, e.g. ``channel_name(412.5, "emissive") == "S0.412,5nm"``."""
    return f"{_COMPONENT[kind]}.{repr(float(wavelength_nm)).replace('.', ',')}nm"


def write_spectral_exr(
    path: str | Path,
    cube: np.ndarray,
    grid: WavelengthGrid,
    *,
    kind: ImageKind = "emissive",
    emissive_units: str = "W.m^-2.sr^-1",
    attributes: dict[str, str] | None = None,
) -> Path:
    """Write ``cube`` ``(H, W, K)`` (float32 or float16, band axis last) as a spectral EXR.

    Parameters
    ----------
    path
        Target file; its folder must exist.
    cube
        Pixel values; the dtype is kept, so a float32 cube round-trips bit-exactly.
    grid
        Wavelengths of the band axis.
    kind
        ``"emissive"`` (``S0`` channels, e.g. radiance) or ``"reflective"`` (``T`` channels).
    emissive_units
        The layout's ``emissiveUnits`` attribute for emissive images.
    attributes
        Extra string attributes for the header (provenance, e.g. the source capture).

    Returns
    -------
    pathlib.Path
        The written file.
    """
    if kind not in _COMPONENT:
        raise InputError(f"kind: expected 'emissive' or 'reflective', got {kind!r}")
    cube = np.asarray(cube)
    if cube.ndim != 3 or cube.shape[-1] != grid.size:
        raise InputError(
            f"cube: expected shape (H, W, {grid.size}) for a grid of {grid.describe()}, got "
            f"{cube.shape}"
        )
    if cube.dtype not in _PIXEL_TYPES:
        raise InputError(f"cube: expected float32 or float16 pixels, got {cube.dtype}")
    path = Path(path)
    if not path.parent.is_dir():
        raise InputError(f"path: folder {path.parent} does not exist")
    header: dict[str, object] = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "spectralLayoutVersion": "1.0",
    }
    if kind == "emissive":
        header["emissiveUnits"] = emissive_units
    header.update(attributes or {})
    channels = {
        channel_name(wavelength, kind): np.ascontiguousarray(cube[..., index])
        for index, wavelength in enumerate(grid.wavelengths_nm)
    }
    handle, temporary = tempfile.mkstemp(suffix=".exr", dir=path.parent)
    os.close(handle)
    try:
        with OpenEXR.File(header, channels) as exr:
            exr.write(temporary)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)
    return path


def read_spectral_exr(path: str | Path) -> SpectralImage:
    """Read a spectral EXR written in the Fichet et al. (2021) layout.

    Returns the emissive (``S0``) channels, or the reflective (``T``) ones when there are no
    emissive channels, sorted by wavelength; other channels (e.g. an RGB preview) are ignored.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"spectral EXR {path} does not exist")
    found: dict[str, dict[float, np.ndarray]] = {"S0": {}, "T": {}}
    with OpenEXR.File(str(path)) as exr:
        # The header and channel dicts are views into the open file: copy what is needed.
        attributes = {
            key: value
            for key, value in exr.header().items()
            if key not in ("channels", "dataWindow", "displayWindow")
        }
        channels = exr.channels()
        channel_names = sorted(channels)
        for name, channel in channels.items():
            match = _CHANNEL_PATTERN.match(name)
            if match:
                pixels = np.array(channel.pixels, copy=True)
                found[match.group(1)][float(match.group(2).replace(",", "."))] = pixels
    component = "S0" if found["S0"] else "T"
    if not found[component]:
        raise InputError(
            f"{path}: expected spectral channels named like 'S0.550,0nm' or 'T.550,0nm' "
            f"(Fichet et al. 2021), found {channel_names}"
        )
    wavelengths = sorted(found[component])
    cube = np.stack([found[component][wavelength] for wavelength in wavelengths], axis=-1)
    kind: ImageKind = "emissive" if component == "S0" else "reflective"
    return SpectralImage(cube, WavelengthGrid(np.asarray(wavelengths)), kind, attributes)
