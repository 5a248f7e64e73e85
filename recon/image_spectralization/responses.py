"""The camera's spectral response: one of the measured cameras that ship with spectwin, by name,
or a CSV ``wavelength_nm,R,G,B`` (what ``spectwin camchar`` writes, and the layout of the
measured cameras in ``recon/data/spectra/cameras_rawtoaces``).

The response's scale does not matter: :mod:`recon.image_spectralization.run` fits a gain per
channel to the spots.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.measured_data import read_camera_sensitivities
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["camera_response", "read_response_csv"]

_HEADER = ["wavelength_nm", "R", "G", "B"]


def read_response_csv(path: str | Path) -> SampledSpectra:
    """Read a response CSV ``wavelength_nm,R,G,B`` (comment lines start with ``#``).

    Returns
    -------
    SampledSpectra
        ``(3, K)`` rows R, G, B.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"response {path}: no such file; expected a CSV wavelength_nm,R,G,B")
    try:
        lines = [
            (number, line)
            for number, line in enumerate(path.read_text().splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")
        ]
    except UnicodeDecodeError:
        raise InputError(f"response {path}: not a text file; expected a CSV") from None
    header = [cell.strip() for cell in lines[0][1].split(",")] if lines else []
    if header != _HEADER:
        raise InputError(
            f"response {path}: header {lines[0][1] if lines else ''!r}; expected "
            f"{','.join(_HEADER)}"
        )
    rows = []
    for number, line in lines[1:]:
        try:
            row = [float(cell) for cell in line.split(",")]
        except ValueError:
            row = []
        if len(row) != 4 or not np.all(np.isfinite(row)):
            raise InputError(
                f"response {path}: line {number} {line.strip()!r}; expected four finite numbers "
                "(wavelength in nm, R, G, B)"
            )
        rows.append(row)
    if len(rows) < 2:
        raise InputError(f"response {path}: {len(rows)} wavelength(s); expected at least 2")
    table = np.array(rows)
    try:
        grid = WavelengthGrid(table[:, 0])
    except InputError as error:
        raise InputError(f"response {path}: {error}") from None
    if np.any(table[:, 1:] < 0) or np.any(table[:, 1:].max(axis=0) <= 0):
        raise InputError(
            f"response {path}: expected non-negative values with some positive one per channel"
        )
    return SampledSpectra(grid, table[:, 1:].T, ("R", "G", "B"))


def camera_response(name_or_csv: str) -> SampledSpectra:
    """A measured camera's response by name (:func:`recon.measured_data.camera_names`:
    ``"Nikon D850"``, ``Nikon_D850``), or a response CSV (:func:`read_response_csv`) when
    ``name_or_csv`` ends in ``.csv`` or names a file.

    Returns
    -------
    SampledSpectra
        ``(3, K)`` rows R, G, B, relative units.
    """
    if name_or_csv.lower().endswith(".csv") or Path(name_or_csv).is_file():
        return read_response_csv(name_or_csv)
    return read_camera_sensitivities(name_or_csv)
