"""Spectral images as ENVI files: a flat binary ``.raw`` file and its text header ``.hdr``.

The format of the ENVI image-analysis software, which remote-sensing and museum-imaging tools
read (ENVI, QGIS/GDAL, Spectronon, the ``spectral`` Python package). What is written:

- ``<stem>.raw``: float32, little-endian (``byte order = 0``, ``data type = 4``), no header
  bytes, band sequential (``bsq``: band after band, each row by row) or band interleaved by line
  (``bil``: per image row, that row in every band);
- ``<stem>.hdr``: ``ENVI`` on the first line, then ``samples`` (columns), ``lines`` (rows),
  ``bands``, ``header offset = 0``, ``file type = ENVI Standard``, ``data type``,
  ``interleave``, ``byte order``, ``wavelength units = Nanometers`` and ``wavelength = {...}``,
  one value per band, and a ``description``.

Both files are written to temporary names and renamed, the header last, so that a failed write
never leaves a header that describes a missing or partial raster.

References
----------
- NV5 Geospatial (L3Harris), ENVI Header Files (``.hdr``), the ENVI documentation.
"""

from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from recon.errors import DamagedDataError, InputError, MissingDataError
from recon.spectra import WavelengthGrid

__all__ = ["ENVI_INTERLEAVES", "EnviImage", "read_envi", "write_envi"]

Interleave = Literal["bsq", "bil"]
ENVI_INTERLEAVES: tuple[Interleave, ...] = ("bsq", "bil")
_FLOAT32 = 4  # ENVI's data type code of 32-bit IEEE floating point
_FIELD = re.compile(r"^\s*([^=]+?)\s*=\s*(.*)$")


@dataclass(frozen=True, eq=False)
class EnviImage:
    """An ENVI image read back: ``cube`` ``(lines, samples, bands)`` (a read-only memory map
    in the file's layout, viewed band axis last) on ``grid``, and the header's ``fields``."""

    cube: np.ndarray
    grid: WavelengthGrid
    fields: dict[str, str]


def _replace_atomically(path: Path, data: bytes) -> None:
    handle, temporary = tempfile.mkstemp(suffix=path.suffix, dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def _header(shape: tuple[int, int, int], grid: WavelengthGrid, interleave: str, text: str) -> str:
    lines, samples, bands = shape
    wavelengths = ", ".join(f"{value:g}" for value in grid.wavelengths_nm)
    description = text.replace("{", "(").replace("}", ")")
    return (
        "ENVI\n"
        f"description = {{{description}}}\n"
        f"samples = {samples}\n"
        f"lines = {lines}\n"
        f"bands = {bands}\n"
        "header offset = 0\n"
        "file type = ENVI Standard\n"
        f"data type = {_FLOAT32}\n"
        f"interleave = {interleave}\n"
        "byte order = 0\n"
        "wavelength units = Nanometers\n"
        f"wavelength = {{{wavelengths}}}\n"
    )


def write_envi(
    stem: str | Path,
    cube: np.ndarray,
    grid: WavelengthGrid,
    *,
    interleave: Interleave = "bsq",
    description: str = "spectral image",
) -> tuple[Path, Path]:
    """Write ``cube`` ``(H, W, K)`` as ``<stem>.hdr`` and ``<stem>.raw`` (module description).

    Parameters
    ----------
    stem
        The files' path without suffix; its folder must exist.
    cube
        Pixel values, band axis last; written as little-endian float32.
    grid
        Wavelengths of the band axis, in nm.
    interleave
        ``"bsq"`` (band sequential) or ``"bil"`` (band interleaved by line).
    description
        The header's ``description`` (braces become parentheses).

    Returns
    -------
    tuple of pathlib.Path
        The header and the raster.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from pathlib import Path
    >>> cube = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    >>> folder = Path(tempfile.mkdtemp())
    >>> header, raster = write_envi(folder / "cube", cube, WavelengthGrid([450, 500, 550, 600]))
    >>> bool(np.array_equal(read_envi(header).cube, cube))
    True
    """
    if interleave not in ENVI_INTERLEAVES:
        raise InputError(f"interleave: expected one of {ENVI_INTERLEAVES}, got {interleave!r}")
    values = np.asarray(cube)
    if values.ndim != 3 or values.shape[-1] != grid.size:
        raise InputError(
            f"cube: expected shape (H, W, {grid.size}) for a grid of {grid.describe()}, got "
            f"{values.shape}"
        )
    stem = Path(stem)
    if not stem.parent.is_dir():
        raise InputError(f"stem: folder {stem.parent} does not exist")
    order = (2, 0, 1) if interleave == "bsq" else (0, 2, 1)
    raster = np.ascontiguousarray(values.transpose(order), dtype="<f4")
    header_path, raster_path = stem.with_suffix(".hdr"), stem.with_suffix(".raw")
    _replace_atomically(raster_path, raster.tobytes())
    lines, samples, _ = values.shape
    header = _header((lines, samples, grid.size), grid, interleave, description)
    _replace_atomically(header_path, header.encode("ascii", "replace"))
    return header_path, raster_path


def _fields(path: Path) -> dict[str, str]:
    """The header's ``name = value`` fields, values in braces joined over their lines."""
    text = path.read_text(errors="replace")
    if not text.startswith("ENVI"):
        raise DamagedDataError(f"{path}: not an ENVI header (expected 'ENVI' on the first line)")
    fields: dict[str, str] = {}
    pending: tuple[str, str] | None = None
    for line in text.splitlines()[1:]:
        if pending is not None:
            name, value = pending
            value = f"{value} {line.strip()}"
            pending = (name, value) if "}" not in line else None
            fields[name] = value
            continue
        match = _FIELD.match(line)
        if match is None:
            continue
        name, value = match.group(1).lower(), match.group(2).strip()
        fields[name] = value
        if value.startswith("{") and "}" not in value:
            pending = (name, value)
    return fields


def _integer(fields: dict[str, str], name: str, path: Path) -> int:
    try:
        return int(fields[name])
    except (KeyError, ValueError):
        raise DamagedDataError(f"{path}: expected an integer '{name}' field") from None


def read_envi(header: str | Path) -> EnviImage:
    """Read an ENVI image of float32 or float64 values (``bsq``, ``bil`` or ``bip``) as a memory
    map, from its header ``<stem>.hdr`` and the raster beside it (``<stem>.raw``, ``.img``,
    ``.dat`` or ``<stem>`` alone).

    Returns
    -------
    EnviImage
    """
    path = Path(header)
    if not path.is_file():
        raise MissingDataError(f"ENVI header {path} does not exist")
    fields = _fields(path)
    lines, samples, bands = (_integer(fields, name, path) for name in ("lines", "samples", "bands"))
    kinds = {4: "f4", 5: "f8"}
    data_type = _integer(fields, "data type", path)
    if data_type not in kinds:
        raise DamagedDataError(f"{path}: data type {data_type}; expected 4 or 5 (float32, float64)")
    dtype = np.dtype(("<" if fields.get("byte order", "0") == "0" else ">") + kinds[data_type])
    interleave = fields.get("interleave", "bsq").lower()
    layouts = {"bsq": (bands, lines, samples), "bil": (lines, bands, samples)}
    layouts["bip"] = (lines, samples, bands)
    if interleave not in layouts:
        raise DamagedDataError(f"{path}: interleave {interleave!r}; expected bsq, bil or bip")
    candidates = [path.with_suffix(suffix) for suffix in (".raw", ".img", ".dat", "")]
    raster = next((candidate for candidate in candidates if candidate.is_file()), None)
    if raster is None:
        raise MissingDataError(f"{path}: its raster ({path.with_suffix('.raw')}) does not exist")
    offset = int(fields.get("header offset", "0"))
    expected = offset + lines * samples * bands * dtype.itemsize
    if raster.stat().st_size != expected:
        raise DamagedDataError(
            f"{raster}: {raster.stat().st_size} bytes; the header describes {expected}"
        )
    stored = np.memmap(raster, dtype=dtype, mode="r", offset=offset, shape=layouts[interleave])
    axes = {"bsq": (1, 2, 0), "bil": (0, 2, 1), "bip": (0, 1, 2)}[interleave]
    wavelengths = fields.get("wavelength", "").strip("{} ")
    try:
        grid = WavelengthGrid(np.array([float(value) for value in wavelengths.split(",")]))
    except ValueError:
        raise DamagedDataError(f"{path}: expected 'wavelength = {{...}}', one per band") from None
    if grid.size != bands:
        raise DamagedDataError(f"{path}: {grid.size} wavelengths for {bands} bands")
    return EnviImage(stored.transpose(axes), grid, fields)
