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

from recon.errors import DamagedDataError, InputError, MissingDataError
from recon.spectra import WavelengthGrid

__all__ = [
    "SpectralImage",
    "SpectralLayout",
    "channel_name",
    "read_spectral_exr",
    "read_spectral_layout",
    "write_spectral_exr",
]

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


@dataclass(frozen=True)
class SpectralLayout:
    """What a spectral EXR's header says, read without its pixels: ``shape`` ``(H, W)``, the
    wavelengths of the channels read and their kind."""

    shape: tuple[int, int]
    grid: WavelengthGrid
    kind: ImageKind


def read_spectral_layout(path: str | Path) -> SpectralLayout:
    """The size, wavelengths and kind of a spectral EXR from its header alone (no pixel is
    read), chosen as :func:`read_spectral_exr` chooses its channels.

    Parameters
    ----------
    path
        A spectral EXR in the Fichet et al. (2021) layout.

    Returns
    -------
    SpectralLayout
        Its size, wavelengths and kind.
    """
    path = _existing(path)
    try:
        with OpenEXR.File(str(path), header_only=True) as exr:
            header = exr.header()
            names = [channel.name for channel in header["channels"]]
            low, high = (np.asarray(corner, np.int64) for corner in header["dataWindow"])
    except (RuntimeError, ValueError) as error:
        raise _unreadable(path, error) from None
    component, wavelengths = _spectral_channels(path, names)
    width, height = (high - low + 1).tolist()
    return SpectralLayout(
        (int(height), int(width)), WavelengthGrid(np.asarray(sorted(wavelengths))), component
    )


def _existing(path: str | Path) -> Path:
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"spectral EXR {path} does not exist")
    return path


def _unreadable(path: Path, error: Exception) -> DamagedDataError:
    return DamagedDataError(f"{path}: not a readable EXR ({' '.join(str(error).split())[:120]})")


def _spectral_channels(path: Path, names: list[str]) -> tuple[ImageKind, dict[float, str]]:
    """The kind of the channels read (emissive ``S0`` where there are any, else reflective
    ``T``) and their names by wavelength."""
    found: dict[str, dict[float, str]] = {"S0": {}, "T": {}}
    for name in names:
        match = _CHANNEL_PATTERN.match(name)
        if match:
            found[match.group(1)][float(match.group(2).replace(",", "."))] = name
    component = "S0" if found["S0"] else "T"
    if not found[component]:
        raise InputError(
            f"{path}: expected spectral channels named like 'S0.550,0nm' or 'T.550,0nm' "
            f"(Fichet et al. 2021), found {sorted(names)}"
        )
    kind: ImageKind = "emissive" if component == "S0" else "reflective"
    return kind, found[component]


def read_spectral_exr(path: str | Path) -> SpectralImage:
    """Read a spectral EXR written in the Fichet et al. (2021) layout.

    Returns the emissive (``S0``) channels, or the reflective (``T``) ones when there are no
    emissive channels, sorted by wavelength; other channels (e.g. an RGB preview) are ignored.
    """
    path = _existing(path)
    try:
        with OpenEXR.File(str(path)) as exr:
            # The header and channel dicts are views into the open file: copy what is needed.
            attributes = {
                key: value
                for key, value in exr.header().items()
                if key not in ("channels", "dataWindow", "displayWindow")
            }
            channels = exr.channels()
            kind, names = _spectral_channels(path, list(channels))
            wavelengths = sorted(names)
            cube = np.stack(
                [np.array(channels[names[nm]].pixels, copy=True) for nm in wavelengths], axis=-1
            )
    except InputError:
        raise
    except (RuntimeError, ValueError) as error:
        raise _unreadable(path, error) from None
    return SpectralImage(cube, WavelengthGrid(np.asarray(wavelengths)), kind, attributes)
