"""A characterization against a measured response.

Two kinds of measurement are compared, each a CSV file:

- response curves, ``wavelength_nm,R,G,B`` (the layout of ``recon.chart_photos.spectra_files``,
  e.g. a monochromator measurement or ``recon/data/spectra/cameras_rawtoaces``), compared over
  the wavelengths both cover (at least 400-700 nm) as curves, :math:`R^{eff}` after one global
  scale (the worst channel's RMSE in % of the true peak, as ``recon.metrics.peak_relative_rmse``
  and thesis 9.4.2 score an estimate), and through each light;
- the camera's white balance under each light, ``light,R,G,B``: the device RGB of a white
  surface under each light of the photographs (any scale per row), a row per light, its label
  the light as given (a name, ``FILE.csv:COLUMN`` or just the ``COLUMN``), compared through each
  light only. This is what a set of narrow-band lights measures, e.g. the Flea3's
  ``sensor_map_relative`` of ``recon/data/real/llanos2019`` (R/G and B/G per band-pass filter).

Through each light: the response to a white surface under the light, :math:`\\sum_i L_i
R^{eff}_{i,c}` (Eq. 9.4 with :math:`S = 1`), as ratios to green, against the measured ratios:
the worst channel's RMSE over the lights in % of the largest measured ratio (no scale fitted:
ratios have none). Narrow-band lights fix a response only inside their passbands, and only up
to a scale per light (each photograph's shading absorbs its intensity), so this is the
comparison they support.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.chart_photos.characterize import REQUIRED_RANGE_NM, PhotoCharacterization
from recon.chart_photos.spectra_files import read_spectra_file, split_column
from recon.errors import InputError
from recon.metrics import peak_relative_rmse
from recon.spectra import SampledSpectra, WavelengthGrid, resample

__all__ = [
    "MeasuredResponse",
    "TruthErrors",
    "check_truth",
    "read_truth",
    "truth_errors",
    "truth_on_grid",
]


@dataclass(frozen=True, eq=False)
class MeasuredResponse:
    """A measured response: ``curves`` ``(3, K)`` rows R, G, B, or ``white_balance``, label ->
    ``(3,)`` device RGB of a white surface under that light (module description)."""

    source: str
    curves: SampledSpectra | None = None
    white_balance: dict[str, np.ndarray] | None = None


@dataclass(frozen=True)
class TruthErrors:
    """Per channel R, G, B in percent: ``curve_pct`` (None for a white balance) and
    ``per_light_pct`` (module description); ``range_nm``, the wavelengths compared."""

    curve_pct: np.ndarray | None
    per_light_pct: np.ndarray
    range_nm: tuple[float, float]


def read_truth(path: str | Path) -> MeasuredResponse:
    """Read a measured response (module description), either kind, from a CSV file."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"truth {path}: no such file; expected a CSV file")
    lines = [
        (number, line)
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), start=1)
        if line.strip() and not line.startswith("#")
    ]
    if not lines or not lines[0][1].lower().startswith("light,"):
        curves = read_spectra_file(path, "truth")
        if curves.values.shape[0] != 3 or not np.all(curves.values.max(axis=1) > 0):
            raise InputError(
                f"truth {path}: expected three columns R, G, B with a positive peak each"
            )
        return MeasuredResponse(str(path), curves=curves)
    balance = {}
    for number, line in lines[1:]:
        label, *fields = (field.strip() for field in line.split(","))
        try:
            values = np.array([float(field) for field in fields])
        except ValueError:
            values = np.empty(0)
        if values.shape != (3,) or not np.all(np.isfinite(values)) or not values[1] > 0:
            raise InputError(
                f"truth {path}, line {number}: expected 'light,R,G,B' with finite values and a "
                "positive G"
            )
        balance[label] = values
    if not balance:
        raise InputError(f"truth {path}: expected a row 'light,R,G,B' per light")
    return MeasuredResponse(str(path), white_balance=balance)


def _labels(light: str) -> tuple[str, ...]:
    """The labels a row of a white balance may give ``light``: itself, and for
    ``FILE:COLUMN`` its column."""
    _, column = split_column(light)
    return (light,) if column is None else (light, column)


def check_truth(truth: MeasuredResponse, grid: WavelengthGrid, lights: Sequence[str]) -> np.ndarray:
    """Where on ``grid`` ``truth`` is compared, ``(K,)`` bool; refuses curves that miss part of
    400-700 nm there, and a white balance without a row for one of ``lights``."""
    wavelengths = grid.wavelengths_nm
    if truth.curves is None:
        balance = truth.white_balance or {}
        missing = [light for light in lights if not set(_labels(light)) & set(balance)]
        if missing:
            raise InputError(
                f"truth {truth.source}: no row for the lights {missing}; expected one per light, "
                f"labelled as given (or by its column), got {sorted(balance)}"
            )
        return np.ones(wavelengths.size, bool)
    curves = truth.curves
    inside = (wavelengths >= curves.grid.start_nm) & (wavelengths <= curves.grid.stop_nm)
    compared = wavelengths[inside]
    if (
        compared.size < 2
        or compared[0] > REQUIRED_RANGE_NM[0]
        or compared[-1] < REQUIRED_RANGE_NM[1]
    ):
        raise InputError(
            f"truth {truth.source}: covers {curves.grid.start_nm:g}-{curves.grid.stop_nm:g} nm; "
            f"expected at least {REQUIRED_RANGE_NM[0]:g}-{REQUIRED_RANGE_NM[1]:g} nm of the "
            f"estimate's {wavelengths[0]:g}-{wavelengths[-1]:g} nm"
        )
    return inside


def truth_on_grid(result: PhotoCharacterization, truth: MeasuredResponse) -> np.ndarray | None:
    """Measured curves on the estimate's grid, ``(K, 3)``, NaN outside their range; None for a
    white balance."""
    if truth.curves is None:
        return None
    grid = WavelengthGrid(result.wavelengths_nm)
    inside = check_truth(truth, grid, result.lights)
    on_grid = np.full((grid.size, 3), np.nan)
    on_grid[inside] = resample(
        truth.curves,
        WavelengthGrid(grid.wavelengths_nm[inside]),
        method="box",
        out_of_range="clamp",
    ).values.T
    return on_grid


def truth_errors(result: PhotoCharacterization, truth: MeasuredResponse) -> TruthErrors:
    """Compare ``result`` with ``truth`` (module description)."""
    inside = check_truth(truth, WavelengthGrid(result.wavelengths_nm), result.lights)
    lights = result.light_spectra[:, inside]
    estimate = result.response[inside]
    white_estimate = lights @ estimate  # (P, 3)
    measured = truth_on_grid(result, truth)
    if measured is not None:
        curves = measured[inside]
        curve_pct = 100 * peak_relative_rmse(estimate, curves)
        white_true = lights @ curves
    else:
        balance = truth.white_balance or {}
        curve_pct = None
        white_true = np.array(
            [
                next(balance[label] for label in _labels(light) if label in balance)
                for light in result.lights
            ]
        )
    if np.any(white_true[:, 1] <= 0) or np.any(white_estimate[:, 1] <= 0):
        raise InputError(f"truth {truth.source}: no green response under one of the lights")
    per_light = peak_relative_rmse(
        white_estimate / white_estimate[:, 1:2], white_true / white_true[:, 1:2], fit_scale=False
    )
    compared = result.wavelengths_nm[inside]
    return TruthErrors(
        curve_pct=curve_pct,
        per_light_pct=100 * per_light,
        range_nm=(float(compared[0]), float(compared[-1])),
    )
