"""Reflectance targets: the Zenith Ultra-White standard, the ColorChecker, the Esser chart and a
240-field chart of measured reflectances for characterizing cameras.

References
----------
- The thesis, Eq. 3.3 and Fig. 3.5d (Zenith Ultra-White reflectance standard of Sphere Optics,
  barium sulphate, nearly perfect white and diffuse); section 9.3 (colour charts).
- Ohta, N. ColorChecker spectra as shipped by ``colour`` ("ColorChecker N Ohta").
- isetbio (MIT licence): ``recon/data/spectra/reflectances/macbeth_colorchecker.csv``.
- rawtoaces-data (Apache-2.0): the 190 training reflectances of ACES camera characterization,
  ``recon/data/spectra/reflectances/rawtoaces_training_190.csv``.
"""

from __future__ import annotations

import colour
import numpy as np

from recon.chart_photos.charts import colorchecker_reflectances as measured_colorchecker
from recon.errors import InputError
from recon.measured_data import read_spectra_csv
from recon.spectra import OutOfRangePolicy, SampledSpectra, WavelengthGrid, from_colour, resample

__all__ = [
    "COLORCHECKER_SOURCES",
    "camera_chart_reflectances",
    "colorchecker_reflectances",
    "esser_reflectances",
    "zenith_white_reflectance",
]

COLORCHECKER_SOURCES = ("ColorChecker N Ohta", "BabelColor Average", "isetbio")


def zenith_white_reflectance(
    grid: WavelengthGrid,
    *,
    plateau: float = 0.99,
    blue_drop: float = 0.03,
    drop_scale_nm: float = 50.0,
) -> SampledSpectra:
    """Directional-hemispherical reflectance of the Zenith Ultra-White standard (Fig. 3.5d).

    A smooth model of the manufacturer's curve: a plateau near 0.99 that falls slightly toward
    the ultraviolet, :math:`W(\\lambda) = p - d\\, e^{-(\\lambda - 350)/s}`.
    """
    if not 0 < plateau <= 1 or not 0 <= blue_drop < plateau or not drop_scale_nm > 0:
        raise InputError(
            "zenith white: expected 0 < plateau <= 1, 0 <= blue_drop < plateau, drop_scale_nm > 0"
        )
    values = plateau - blue_drop * np.exp(-(grid.wavelengths_nm - 350.0) / drop_scale_nm)
    return SampledSpectra(grid, np.clip(values, 0.0, 1.0))


def colorchecker_reflectances(
    grid: WavelengthGrid,
    *,
    source: str = "ColorChecker N Ohta",
    out_of_range: OutOfRangePolicy = "error",
) -> SampledSpectra:
    """The 24 ColorChecker patch reflectances, values ``(24, K)`` named by patch.

    ``source`` is a chart of ``colour.SDS_COLOURCHECKERS`` or ``"isetbio"`` (the measured chart
    in spectwin's data); ``out_of_range`` says how to extend the data (380-780 nm for ``colour``)
    to a wider grid (see ``recon.spectra.resample``).
    """
    if source not in COLORCHECKER_SOURCES:
        raise InputError(f"source: expected one of {COLORCHECKER_SOURCES}, got {source!r}")
    names = tuple(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"])
    if source == "isetbio":
        measured = measured_colorchecker()
    else:
        patches = colour.SDS_COLOURCHECKERS[source]
        measured = from_colour(colour.MultiSpectralDistributions(list(patches.values())))
        measured = SampledSpectra(measured.grid, measured.values, names)
    return resample(measured, grid, method="pchip", out_of_range=out_of_range)


def esser_reflectances(
    grid: WavelengthGrid, *, brightest: float = 0.9, out_of_range: OutOfRangePolicy = "error"
) -> SampledSpectra:
    """The 113 Esser test chart patches (isetbio data in ``recon/data``), values ``(113, K)``.

    The isetbio table is in relative units (its largest value is about 1.5e-3): it is scaled so
    that the brightest patch has a mean reflectance of ``brightest`` over 400-700 nm.
    """
    measured = read_spectra_csv("spectra/reflectances/esser_chart.csv")
    visible = (measured.wavelengths_nm >= 400) & (measured.wavelengths_nm <= 700)
    scale = brightest / measured.values[:, visible].mean(axis=1).max()
    resampled = resample(measured, grid, method="pchip", out_of_range=out_of_range)
    return SampledSpectra(grid, np.clip(resampled.values * scale, 0.0, 1.0), measured.names)


CAMERA_CHART_FIELDS = 240


def camera_chart_reflectances(grid: WavelengthGrid) -> SampledSpectra:
    """A chart of 240 measured reflectances, 380-780 nm, for characterizing cameras, ``(240, K)``.

    The size of the ColorChecker DC that the thesis photographs (chapter 9), from the measured
    sets that span the 380-780 nm of the measured cameras (``recon.measured_data``), so the
    whole response is constrained:

    - the 185 of rawtoaces' 190 training reflectances that stay within [0, 1] (five exceed one
      near 700-780 nm: fluorescence or measurement artefacts, not diffuse reflectances), the
      set ACES fits camera matrices with;
    - the 24 ColorChecker patches (isetbio's measurement, the thesis's chart family);
    - 31 Esser chart patches chosen farthest first: each is the Esser patch whose RMS distance
      (380-780 nm, 5 nm steps) to the nearest field already on the chart is largest, so the
      chart gains the spectra it lacks most.

    The Vrhel and DuPont sets end at 400 and 700 nm and are left out. The fields are chosen on
    the 5 nm grid of the rawtoaces data and averaged over the cells of ``grid`` (which must lie
    within 380-780 nm), so every grid gets the same fields.
    """
    if grid.start_nm < 380.0 or grid.stop_nm > 780.0:
        raise InputError(f"grid: expected wavelengths within 380-780 nm, got {grid.describe()}")
    training = read_spectra_csv("spectra/reflectances/rawtoaces_training_190.csv")
    diffuse = training.values.max(axis=1) <= 1.0
    macbeth = read_spectra_csv("spectra/reflectances/macbeth_colorchecker.csv")
    fields = np.concatenate(
        [training.values[diffuse], resample(macbeth, training.grid, method="box").values]
    )
    names = [name for name, kept in zip(training.names or (), diffuse, strict=True) if kept]
    names += [f"colorchecker {name}" for name in macbeth.names or ()]
    esser = esser_reflectances(training.grid).values
    distance = np.sqrt(((esser[:, None, :] - fields[None]) ** 2).mean(axis=2)).min(axis=1)
    for _ in range(CAMERA_CHART_FIELDS - len(fields)):
        chosen = int(np.argmax(distance))
        fields = np.vstack([fields, esser[chosen]])
        names.append(f"esser {chosen + 1}")
        distance = np.minimum(distance, np.sqrt(((esser - esser[chosen]) ** 2).mean(axis=1)))
    chart = SampledSpectra(training.grid, fields, tuple(names))
    if grid != training.grid:
        chart = resample(chart, grid, method="box", out_of_range="clamp")
    return SampledSpectra(grid, np.clip(chart.values, 0.0, 1.0), chart.names)  # rounding
