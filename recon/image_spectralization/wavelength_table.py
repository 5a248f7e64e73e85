"""A user's spectra as a CSV table by wavelength: the header ``wavelength_nm`` then one named
column per spectrum, one row per wavelength (the layout of spectwin's measured data,
:mod:`recon.measured_data`, and of spectrometers' exports); lines starting with ``#`` are
comments. What the columns hold (a camera's response, a reflectance reading) is the caller's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["csv_lines", "read_wavelength_table"]


def csv_lines(path: Path, what: str, expected: str) -> list[tuple[int, str]]:
    """The numbered lines of the CSV file at ``path`` that are neither blank nor comments
    (``#``), refusing in one line (prefixed by ``what`` and the path) a missing file, naming
    ``expected``, or one that is not text."""
    if not path.is_file():
        raise InputError(f"{what} {path}: no such file; expected {expected}")
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise InputError(f"{what} {path}: not a text file; expected a CSV") from None
    return [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]


def read_wavelength_table(path: str | Path, columns: tuple[str, ...], what: str) -> SampledSpectra:
    """Read a table ``wavelength_nm,<columns>`` (module description), refusing in one line
    (prefixed by ``what`` and the path) a missing file, another header, a row that is not
    ``1 + len(columns)`` finite numbers, fewer than two wavelengths or wavelengths that do not
    increase.

    Returns
    -------
    SampledSpectra
        ``(len(columns), K)``, rows named by ``columns``.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> path = Path(tempfile.mkdtemp()) / "reading.csv"
    >>> _ = path.write_text("wavelength_nm,reflectance\\n400,0.1\\n500,0.2\\n")
    >>> read_wavelength_table(path, ("reflectance",), "reading").values.tolist()
    [[0.1, 0.2]]
    """
    path = Path(path)
    header = ["wavelength_nm", *columns]
    expected = ",".join(header)
    lines = csv_lines(path, what, f"a CSV {expected}")
    found = [cell.strip() for cell in lines[0][1].split(",")] if lines else []
    if found != header:
        raise InputError(
            f"{what} {path}: header {lines[0][1] if lines else ''!r}; expected {expected}"
        )
    rows = []
    for number, line in lines[1:]:
        try:
            row = [float(cell) for cell in line.split(",")]
        except ValueError:
            row = []
        if len(row) != len(header) or not np.all(np.isfinite(row)):
            raise InputError(
                f"{what} {path}: line {number} {line.strip()!r}; expected {len(header)} finite "
                f"numbers ({', '.join(['wavelength in nm', *columns])})"
            )
        rows.append(row)
    if len(rows) < 2:
        raise InputError(f"{what} {path}: {len(rows)} wavelength(s); expected at least 2")
    table = np.array(rows)
    try:
        grid = WavelengthGrid(table[:, 0])
    except InputError as error:
        raise InputError(f"{what} {path}: {error}") from None
    return SampledSpectra(grid, table[:, 1:].T, columns)
