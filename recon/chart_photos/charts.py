"""Colour charts for camera characterization: the reflectances of their patches and their layout.

A chart is a grid of ``rows x columns`` patches of known spectral reflectance, in reading order
(left to right, top to bottom, the first patch at the chart's first corner). Named charts are
those whose reflectances ship with spectwin:

- ``colorchecker``: the X-Rite ColorChecker Classic, 4 x 6 patches, reflectances measured by
  isetbio (``recon/data/spectra/reflectances/macbeth_colorchecker.csv``, MIT licence),
  380-1068 nm, the first patch "dark skin" and the grey series in the last row.

The 113-patch Esser chart's data in ``recon/data`` is in relative units and says nothing of its
layout, and no ColorChecker SG data ships with spectwin: such charts come as a CSV of their
reflectances with their layout (:func:`chart_from_csv`).

References
----------
- McCamy, C. S., Marcus, H., & Davidson, J. G. (1976). A color-rendition chart. Journal of
  Applied Photographic Engineering, 2(3), 95-99.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from recon.chart_photos.spectra_files import read_spectra_file
from recon.errors import InputError
from recon.measured_data import read_spectra_csv
from recon.spectra import SampledSpectra

__all__ = ["CHARTS", "Chart", "chart_from_csv", "colorchecker_reflectances", "named_chart"]

CHARTS = {"colorchecker": "X-Rite ColorChecker Classic, 24 patches (4 x 6), isetbio's measurement"}
"""The named charts and what they are."""

_LARGEST_FACTOR = 1.2
"""The largest reflectance factor accepted (measurements relative to a white standard exceed 1
a little); larger values are taken for percent or relative units and refused."""


@dataclass(frozen=True, eq=False)
class Chart:
    """A chart: ``reflectances`` ``(rows * columns, K)`` in reading order, named by patch, in
    [0, 1]; ``rows`` and ``columns``; ``name``; ``note``, what was done to the file's values
    (or None)."""

    name: str
    reflectances: SampledSpectra
    rows: int
    columns: int
    note: str | None = None

    @property
    def patch_names(self) -> tuple[str, ...]:
        """The patches' names in reading order."""
        names = self.reflectances.names
        return names if names is not None else tuple(f"patch {j + 1}" for j in range(self.size))

    @property
    def size(self) -> int:
        """Number of patches."""
        return self.rows * self.columns

    def positions(self) -> np.ndarray:
        """``(J, 2)`` the patches' (column, row) on the chart, for the shading neighbourhoods
        of Eq. 9.9."""
        index = np.arange(self.size)
        return np.column_stack([index % self.columns, index // self.columns]).astype(np.float64)


def colorchecker_reflectances() -> SampledSpectra:
    """isetbio's measured ColorChecker Classic, ``(24, K)`` in reading order, 380-1068 nm.

    The file stores the 4 x 6 chart column by column (its grey series is every fourth patch); the
    rows here are in reading order, named as ``colour``'s ColorChecker patches ("dark skin", ...).
    """
    measured = read_spectra_csv("spectra/reflectances/macbeth_colorchecker.csv")
    names = tuple(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"])
    reading_order = [(index % 6) * 4 + index // 6 for index in range(24)]
    return SampledSpectra(measured.grid, measured.values[reading_order], names)


def named_chart(name: str) -> Chart:
    """The chart ``name`` of :data:`CHARTS`."""
    if name != "colorchecker":
        raise InputError(
            f"chart {name!r}: expected one of {sorted(CHARTS)} or a CSV file of reflectances"
        )
    return Chart(name, colorchecker_reflectances(), rows=4, columns=6)


def chart_from_csv(path: str | Path, rows: int, columns: int) -> Chart:
    """A chart from a CSV of its patches' reflectances (``recon.chart_photos.spectra_files``:
    one column per patch, in reading order) laid out in ``rows x columns``.

    Reflectance factors relative to a white standard may exceed 1 a little: values up to 1.2
    are scaled to a largest value of 1 (a global scale, which the shading of Eq. 9.7 absorbs),
    and the chart's ``note`` says so.
    """
    if rows < 1 or columns < 1 or rows * columns < 2:
        raise InputError(f"layout {rows}x{columns}: expected at least 2 patches")
    spectra = read_spectra_file(path, "chart")
    count = spectra.values.shape[0]
    if count != rows * columns:
        raise InputError(
            f"chart {path}: {count} patches; expected {rows * columns} for the layout "
            f"{rows}x{columns} (rows x columns)"
        )
    values = spectra.values
    largest = float(values.max())
    if values.min() < 0 or largest > _LARGEST_FACTOR:
        raise InputError(
            f"chart {path}: reflectances from {values.min():g} to {largest:g}; expected values in "
            f"[0, 1] (factors up to {_LARGEST_FACTOR} relative to a white standard), not percent"
        )
    note = None
    if largest > 1:
        values = values / largest
        note = f"reflectance factors up to {largest:.3g} scaled to a largest value of 1"
    return Chart(
        Path(path).name,
        SampledSpectra(spectra.grid, values, spectra.names),
        rows=rows,
        columns=columns,
        note=note,
    )
