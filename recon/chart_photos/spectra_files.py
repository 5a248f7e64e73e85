"""A user's spectra files: a chart's reflectances, a light, a camera's measured response.

Two layouts are read, both comma-separated with one header line (lines starting with ``#``
are comments):

- spectwin's: ``wavelength_nm,<name>,<name>,...`` (the files of ``recon/data/spectra``);
- a spectrometer's export: ``Wavelength,<name>,...`` (e.g. the ASD measurements of
  ``recon/data/real/llanos2019/spectral_data/spectra_averaged.csv``).

The first column is the wavelength in nm, strictly increasing; every other column is one
spectrum. ``FILE.csv:COLUMN`` names one column of a file of several spectra. Every refusal
names the file and what was expected.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["read_spectra_file", "split_column"]


def split_column(spec: str) -> tuple[Path, str | None]:
    """``FILE`` or ``FILE:COLUMN`` as the file and the column (None for the whole file).

    The text after the last colon names a column only where the whole text is not a file.

    Examples
    --------
    >>> split_column("spectra_averaged.csv:442 nm")
    (PosixPath('spectra_averaged.csv'), '442 nm')
    """
    path = Path(spec)
    head, colon, column = spec.rpartition(":")
    if path.is_file() or not colon or not head:
        return path, None
    return Path(head), column


def read_spectra_file(spec: str | Path, what: str) -> SampledSpectra:
    """The spectra of a CSV file (module description), named by their columns.

    Parameters
    ----------
    spec
        ``FILE`` or ``FILE:COLUMN``.
    what
        What the file holds, for the messages (e.g. ``"light"``).

    Returns
    -------
    SampledSpectra
        ``(columns, K)`` on the file's wavelengths (one row for ``FILE:COLUMN``).
    """
    path, column = split_column(str(spec))
    if not path.is_file():
        raise InputError(f"{what} {spec}: no such file; expected a CSV file of spectra")
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise InputError(
            f"{what} {path}: not a text file; expected a CSV file of spectra"
        ) from None
    lines = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.startswith("#")
    ]
    if len(lines) < 3:
        raise InputError(f"{what} {path}: expected a header and at least 2 rows of wavelengths")
    header = [name.strip() for name in lines[0][1].split(",")]
    if header[0].lower() not in ("wavelength_nm", "wavelength") or len(header) < 2:
        raise InputError(
            f"{what} {path}: expected a header 'wavelength_nm,<name>,...' (or 'Wavelength,...'), "
            f"got {lines[0][1][:60]!r}"
        )
    table = _numbers(lines[1:], len(header), f"{what} {path}")
    names = header[1:]
    if column is not None:
        if column not in names:
            raise InputError(
                f"{what} {path}: no column {column!r}; expected one of {_shown(names)}"
            )
        table = table[:, [0, 1 + names.index(column)]]
        names = [column]
    try:
        grid = WavelengthGrid(table[:, 0])
    except InputError as error:
        raise InputError(f"{what} {path}: {error}") from None
    return SampledSpectra(grid, table[:, 1:].T, tuple(names))


def _numbers(lines: list[tuple[int, str]], columns: int, source: str) -> np.ndarray:
    """The rows as a ``(rows, columns)`` float array, finite; refusing a row that is not."""
    rows = []
    for number, line in lines:
        fields = line.split(",")
        if len(fields) != columns:
            raise InputError(
                f"{source}, line {number}: {len(fields)} values; expected {columns} like the header"
            )
        try:
            row = [float(field) for field in fields]
        except ValueError:
            raise InputError(
                f"{source}, line {number}: expected numbers, got {line[:60]!r}"
            ) from None
        if not np.all(np.isfinite(row)):
            raise InputError(f"{source}, line {number}: NaN or infinity; expected finite values")
        rows.append(row)
    return np.array(rows)


def _shown(names: list[str]) -> str:
    return ", ".join(repr(name) for name in names[:8]) + (", ..." if len(names) > 8 else "")
