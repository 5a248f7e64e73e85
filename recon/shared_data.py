"""Locate and read the measured data in the workplace's ``shared/data`` folder.

The folder sits beside the repository (``../shared/data``) unless the environment variable
``SPECTWIN_SHARED_DATA`` names another location. Spectra there are CSV files whose first column is
``wavelength_nm`` and whose ``#`` lines name the source; see ``shared/data/README.md``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from recon.errors import SpectwinDataError, SpectwinInputError
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = ["read_spectra_csv", "shared_data_dir"]

_ENV_VARIABLE = "SPECTWIN_SHARED_DATA"


def shared_data_dir() -> Path:
    """The ``shared/data`` folder: ``$SPECTWIN_SHARED_DATA`` or ``<repository>/../shared/data``."""
    configured = os.environ.get(_ENV_VARIABLE)
    folder = (
        Path(configured) if configured else Path(__file__).resolve().parents[2] / "shared" / "data"
    )
    if not folder.is_dir():
        raise SpectwinDataError(
            f"shared data folder {folder} does not exist: put the workplace's shared/ beside the "
            f"repository or set {_ENV_VARIABLE} to its data folder"
        )
    return folder


def read_spectra_csv(relative_path: str | Path) -> SampledSpectra:
    """Read a spectra CSV of ``shared/data`` (e.g. ``"spectra/sensors/nikon_d70_rgb.csv"``).

    Returns
    -------
    SampledSpectra
        Values ``(n_columns, K)`` named by the CSV header, on the file's wavelengths.
    """
    path = shared_data_dir() / relative_path
    if not path.is_file():
        raise SpectwinDataError(f"spectra file {path} does not exist")
    lines = [line for line in path.read_text().splitlines() if line and not line.startswith("#")]
    header = [column.strip() for column in lines[0].split(",")]
    if header[0] != "wavelength_nm" or len(header) < 2:
        raise SpectwinInputError(
            f"{path}: expected a header 'wavelength_nm,<name>,...', got {lines[0]!r}"
        )
    table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return SampledSpectra(WavelengthGrid(table[:, 0]), table[:, 1:].T, tuple(header[1:]))
