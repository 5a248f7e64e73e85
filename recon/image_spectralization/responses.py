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
from recon.image_spectralization.wavelength_table import read_wavelength_table
from recon.measured_data import read_camera_sensitivities
from recon.spectra import SampledSpectra

__all__ = ["camera_response", "read_response_csv"]

_CHANNELS = ("R", "G", "B")


def read_response_csv(path: str | Path) -> SampledSpectra:
    """Read a response CSV ``wavelength_nm,R,G,B`` (comment lines start with ``#``;
    :func:`recon.image_spectralization.wavelength_table.read_wavelength_table`).

    Returns
    -------
    SampledSpectra
        ``(3, K)`` rows R, G, B.
    """
    response = read_wavelength_table(path, _CHANNELS, "response")
    if np.any(response.values < 0) or np.any(response.values.max(axis=1) <= 0):
        raise InputError(
            f"response {path}: expected non-negative values with some positive one per channel"
        )
    return response


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
