"""Spot spectra at pixel coordinates, from a CSV file.

The layout: a header ``x,y,<wavelength>,<wavelength>,...`` (wavelengths in nm, increasing),
then one row per spot: its pixel's column ``x`` and row ``y`` (from 0 at the image's top-left
pixel) and its spectrum, one value per wavelength, in whatever unit the spectrometer gave
(reflectance factor or radiance; the reconstruction is in the same unit). Lines starting with
``#`` are comments. Each spot is one pixel; a spot measured over several pixels is given as
several rows, or as a region of a label image: the header ``label,<wavelength>,...``, one row
per label, and an image of whole numbers the size of the RGB image in which a label's pixels
are its measured area (0: no spot). Every pixel of the area takes the label's spectrum: an area
small and uniform enough for one spectrometer reading.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.image_spectralization.wavelength_table import csv_lines
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["SpotSpectra", "read_spot_mask", "read_spot_table", "read_spots_csv"]


@dataclass(frozen=True, eq=False)
class SpotSpectra:
    """``xy`` ``(m, 2)`` int pixel coordinates (column, row) and their ``spectra`` (``m``
    rows), read from ``source``."""

    xy: np.ndarray
    spectra: SampledSpectra
    source: str

    def flat_pixels(self, shape: tuple[int, int]) -> np.ndarray:
        """Row-major indices of the spots in an image of ``shape`` ``(H, W)``, refusing spots
        outside it."""
        height, width = shape
        x, y = self.xy[:, 0], self.xy[:, 1]
        outside = (x < 0) | (y < 0) | (x >= width) | (y >= height)
        if outside.any():
            first = int(np.argmax(outside))
            raise InputError(
                f"spots {self.source}: {int(outside.sum())} spot(s) outside the {width} x "
                f"{height} image, the first at x={x[first]}, y={y[first]} (row {first + 2}); "
                f"expected 0 <= x < {width} and 0 <= y < {height}"
            )
        return y * width + x


def _number(text: str, path: Path, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(
            f"spots {path}: line {line}, column {column}: {text.strip()!r} is not a number"
        ) from None
    if not np.isfinite(value):
        raise InputError(
            f"spots {path}: line {line}, column {column}: {text.strip()}; expected a finite "
            "number (NaN marks no measurement; leave such spots out)"
        )
    return value


def read_spot_table(
    path: str | Path, keys: tuple[str, ...], what: str
) -> tuple[np.ndarray, SampledSpectra]:
    """Read a spot table: a header of the whole-number ``keys`` (e.g. ``x,y``) then wavelengths
    in nm, one row per spot (module description); ``what`` names the keys' meaning in errors
    ("pixel", "texel").

    Returns
    -------
    tuple
        ``(m, len(keys))`` int keys, distinct per row, and the ``m`` spectra.
    """
    path = Path(path)
    names = ",".join(keys)
    lines = csv_lines(path, "spots", f"a CSV of {names} and spectra")
    if not lines:
        raise InputError(f"spots {path}: empty; expected a header {names},<wavelength nm>,...")
    header = [cell.strip() for cell in lines[0][1].split(",")]
    if header[: len(keys)] != list(keys) or len(header) < len(keys) + 2:
        raise InputError(
            f"spots {path}: header {lines[0][1]!r}; expected {names} then at least two "
            f"wavelengths in nm, e.g. {names},400,410,420"
        )
    wavelengths = [_number(cell, path, lines[0][0], "header") for cell in header[len(keys) :]]
    try:
        grid = WavelengthGrid(np.array(wavelengths))
    except InputError as error:
        raise InputError(f"spots {path}: header wavelengths: {error}") from None
    rows = []
    for number, line in lines[1:]:
        cells = line.split(",")
        if len(cells) != len(header):
            raise InputError(
                f"spots {path}: line {number} has {len(cells)} values; expected {len(header)} "
                f"({', '.join(keys)} and one per wavelength)"
            )
        rows.append([_number(c, path, number, h) for c, h in zip(cells, header, strict=True)])
    if not rows:
        raise InputError(f"spots {path}: no spots below the header")
    table = np.array(rows)
    where = table[:, : len(keys)]
    if np.any(where != np.round(where)):
        raise InputError(f"spots {path}: {', '.join(keys)} must be whole {what} coordinates")
    places = where.astype(int)
    _, first, counts = np.unique(places, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        twice = ", ".join(
            f"{key}={value}" for key, value in zip(keys, places[first[counts > 1][0]], strict=True)
        )
        raise InputError(
            f"spots {path}: {what} {twice} is given {counts.max()} times; expected one spectrum "
            f"per {what}"
        )
    return places, SampledSpectra(grid, table[:, len(keys) :])


def read_spots_csv(path: str | Path) -> SpotSpectra:
    """Read spot spectra (module description).

    Returns
    -------
    SpotSpectra

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> path = Path(tempfile.mkdtemp()) / "spots.csv"
    >>> _ = path.write_text("x,y,400,500,600\\n3,4,0.1,0.2,0.3\\n")
    >>> spots = read_spots_csv(path)
    >>> spots.xy.tolist(), spots.spectra.grid.wavelengths_nm.tolist()
    ([[3, 4]], [400.0, 500.0, 600.0])
    """
    pixels, spectra = read_spot_table(path, ("x", "y"), "pixel")
    return SpotSpectra(pixels, spectra, str(path))


def read_spot_mask(path: str | Path, mask: str | Path, rgb: np.ndarray) -> SpotSpectra:
    """Read spot spectra by label (module description) and the label image ``mask`` that
    places them in the linear RGB image ``rgb`` ``(H, W, 3)``.

    Returns
    -------
    SpotSpectra
        One spot per label: the pixel of its area whose camera values are nearest the area's
        mean (the pixel the area's mean spectrum stands for best; every pixel of a textured
        area taking the mean spectrum would contradict its own camera values).
    """
    from recon.image_files import read_png_or_tiff

    labels, spectra = read_spot_table(path, ("label",), "label")
    mask = Path(mask)
    if not mask.is_file():
        raise InputError(
            f"label image {mask}: no such file; expected a PNG or TIFF of whole-number labels"
        )
    image = read_png_or_tiff(mask, "label image")
    if image.ndim != 2 or image.dtype.kind not in "ui":
        raise InputError(
            f"label image {mask}: {image.dtype} values of shape {image.shape}; expected one "
            "channel of whole-number labels (0: no spot)"
        )
    if image.shape != rgb.shape[:2]:
        raise InputError(
            f"label image {mask}: {image.shape[1]} x {image.shape[0]} pixels; expected the RGB "
            f"image's {rgb.shape[1]} x {rgb.shape[0]}"
        )
    xy = []
    for label in labels[:, 0]:
        y, x = np.nonzero(image == label)
        if label <= 0 or x.size == 0:
            raise InputError(
                f"spots {path}: label {label} marks no pixel of the label image {mask}; expected "
                "labels above 0 that the label image holds"
            )
        values = rgb[y, x]
        nearest = np.argmin(np.linalg.norm(values - values.mean(axis=0), axis=1))
        xy.append([x[nearest], y[nearest]])
    return SpotSpectra(np.array(xy), spectra, str(path))
