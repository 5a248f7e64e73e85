"""The light of a chart photograph: by name, or measured, as a CSV spectrum.

Names: the CIE illuminants of ``colour.SDS_ILLUMINANTS`` (``D65``, ``A``, ``FL11``, ``LED-B1``,
...; any case) and the lamps measured by isetbio that ship with spectwin (``tungsten_lab``,
``fluorescent_office``, ``recon/data/spectra/lights``). Anything else is a file:
``FILE.csv`` with one spectrum or ``FILE.csv:COLUMN`` (``recon.chart_photos.spectra_files``),
e.g. a band-pass filter's transmission measured with a spectrometer.

Only the light's relative spectral power matters (thesis 9.4.2 normalizes it to a mean of one).
"""

from __future__ import annotations

import colour
import numpy as np

from recon.chart_photos.spectra_files import read_spectra_file
from recon.errors import InputError
from recon.measured_data import data_path, read_spectra_csv
from recon.spectra import SampledSpectra, from_colour

__all__ = ["light_names", "light_spectrum"]

_NOISE_FLOOR = 0.02
"""Negative values down to this fraction of the peak are a spectrometer's noise and read as zero."""


def _lamps() -> dict[str, str]:
    return {path.stem: path.name for path in sorted(data_path("spectra/lights").glob("*.csv"))}


def light_names() -> tuple[str, ...]:
    """The names :func:`light_spectrum` knows: the CIE illuminants of ``colour`` and the lamps
    of spectwin's data."""
    return (*colour.SDS_ILLUMINANTS, *_lamps())


def light_spectrum(spec: str) -> SampledSpectra:
    """The relative spectral power of the light ``spec`` (module description), one row.

    Returns
    -------
    SampledSpectra
        ``(1, K)`` non-negative, named ``spec``, on the data's own wavelengths.
    """
    illuminants = {name.lower(): name for name in colour.SDS_ILLUMINANTS}
    lamps = _lamps()
    if spec.lower() in illuminants:
        spectrum = from_colour(colour.SDS_ILLUMINANTS[illuminants[spec.lower()]])
        return SampledSpectra(spectrum.grid, spectrum.values[None], (spec,))
    if spec in lamps:
        lamp = read_spectra_csv(f"spectra/lights/{lamps[spec]}")
        return SampledSpectra(lamp.grid, lamp.values[:1], (spec,))
    if not spec.lower().partition(":")[0].endswith((".csv", ".txt")):
        raise InputError(
            f"light {spec!r}: expected a CIE illuminant such as 'D65' or 'A', one of "
            f"{sorted(lamps)}, or a CSV file of its spectrum (FILE.csv or FILE.csv:COLUMN)"
        )
    spectra = read_spectra_file(spec, "light")
    if spectra.values.shape[0] != 1:
        raise InputError(
            f"light {spec}: {spectra.values.shape[0]} spectra; expected one, or one named as "
            "FILE.csv:COLUMN"
        )
    values = spectra.values
    peak = values.max()
    if not peak > 0 or values.min() < -_NOISE_FLOOR * peak:
        raise InputError(
            f"light {spec}: values from {values.min():g} to {peak:g}; expected a non-negative "
            "spectrum with some power"
        )
    return SampledSpectra(spectra.grid, np.clip(values, 0.0, None), (spec,))
