"""A camera's spectral response from real photographs of a chart (thesis chapter 9).

The photographs (``recon.chart_photos.images``) are sampled patch by patch
(``recon.chart_photos.patches``); the photographs under one light are exposures of one scene and
merge into one device RGB per patch; the photographs under different lights are the several
photographs of thesis 9.4, estimated jointly by the extended estimator (Eq. 9.6-9.14,
``recon.camera_char.estimate_response``), by default with the prior learned from the 51
measured cameras that ship with spectwin. Each light's per-photograph shading absorbs its
intensity and exposure, so only the lights' relative spectra matter.

The estimate lives on a 10 nm grid over the wavelengths every input covers, within the 380-780
nm of the measured cameras; the chart and every light must cover at least 400-700 nm. The
residuals of the fit (Eq. 9.7) are reported per photograph and patch; a measured response is
compared by ``recon.chart_photos.truth``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from recon.camera_char import MeasuredPrior, estimate_response, fit_residuals
from recon.camera_prior import ResponsePrior
from recon.chart_photos.charts import Chart
from recon.chart_photos.images import LinearPhoto
from recon.chart_photos.patches import merge_exposures, sample_patches
from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid, resample

__all__ = [
    "ChartPhotograph",
    "PhotoCharacterization",
    "characterize_photographs",
    "estimation_grid",
]

GRID_STEP_NM = 10.0
CAMERA_RANGE_NM = (380.0, 780.0)
REQUIRED_RANGE_NM = (400.0, 700.0)


@dataclass(frozen=True, eq=False)
class ChartPhotograph:
    """One photograph: the ``photo``, the name of its ``light``, its ``exposure_s`` and the
    chart's ``corners`` ``(4, 2)`` in it (``recon.chart_photos.patches``)."""

    photo: LinearPhoto
    light: str
    exposure_s: float
    corners: np.ndarray


@dataclass(frozen=True, eq=False)
class PhotoCharacterization:
    """The estimated response and what it was estimated from.

    Attributes
    ----------
    wavelengths_nm
        ``(K,)`` the estimation grid.
    response
        ``(K, 3)`` :math:`R^{eff}` (channels R, G, B), largest value one.
    lights
        The lights, one per merged photograph (in the order of first appearance).
    light_spectra
        ``(P, K)`` their spectra on the grid.
    chart
        The chart, its reflectances on its own grid.
    reflectances
        ``(J, K)`` the chart's reflectances on the grid.
    rgb
        ``(P, J, 3)`` device RGB per patch, exposures merged (per second).
    exposures_used
        ``(P, J, 3)`` how many exposures went into each value.
    residuals
        ``(P, J, 3)`` the fit's residuals (``recon.camera_char.fit_residuals``), in units of
        each photograph's mean device RGB.
    shading, specularity
        ``(P, J)`` :math:`F_j` and :math:`\\sigma_j` of Eq. 9.7.
    """

    wavelengths_nm: np.ndarray
    response: np.ndarray
    lights: tuple[str, ...]
    light_spectra: np.ndarray
    chart: Chart
    reflectances: np.ndarray
    rgb: np.ndarray
    exposures_used: np.ndarray
    residuals: np.ndarray
    shading: np.ndarray
    specularity: np.ndarray


def estimation_grid(chart: Chart, lights: Mapping[str, SampledSpectra]) -> WavelengthGrid:
    """The 10 nm grid over the wavelengths the chart and every light cover, within 380-780 nm
    (module description); refuses spectra that miss part of 400-700 nm."""
    spectra = {f"chart {chart.name}": chart.reflectances.grid}
    spectra.update({f"light {name}": spectrum.grid for name, spectrum in lights.items()})
    for what, grid in spectra.items():
        if grid.start_nm > REQUIRED_RANGE_NM[0] or grid.stop_nm < REQUIRED_RANGE_NM[1]:
            raise InputError(
                f"{what}: covers {grid.start_nm:g}-{grid.stop_nm:g} nm; expected spectra covering "
                f"at least {REQUIRED_RANGE_NM[0]:g}-{REQUIRED_RANGE_NM[1]:g} nm"
            )
    start = max(CAMERA_RANGE_NM[0], *(grid.start_nm for grid in spectra.values()))
    stop = min(CAMERA_RANGE_NM[1], *(grid.stop_nm for grid in spectra.values()))
    return WavelengthGrid.regular(
        GRID_STEP_NM * math.ceil(start / GRID_STEP_NM),
        GRID_STEP_NM * math.floor(stop / GRID_STEP_NM),
        GRID_STEP_NM,
    )


def _on_grid(spectra: SampledSpectra, grid: WavelengthGrid) -> np.ndarray:
    """Cell means on ``grid`` (which lies within the spectra's range)."""
    return resample(spectra, grid, method="box", out_of_range="clamp").values


def characterize_photographs(
    photographs: Sequence[ChartPhotograph],
    chart: Chart,
    lights: Mapping[str, SampledSpectra],
    *,
    prior: ResponsePrior | MeasuredPrior | None = "measured",
    fraction: float = 0.5,
    floor: float = 0.02,
) -> PhotoCharacterization:
    """Estimate a camera's response from photographs of ``chart`` (module description).

    Parameters
    ----------
    photographs
        The photographs, each naming its light.
    chart
        The chart photographed (``recon.chart_photos.charts``).
    lights
        The spectrum ``(1, K)`` of every light a photograph names
        (``recon.chart_photos.lights.light_spectrum``).
    prior
        As :func:`recon.camera_char.estimate_response` takes it: the prior learned from the
        shipped cameras by default, None for the thesis's method.
    fraction, floor
        The window of each patch and the floor of the exposure merge
        (``recon.chart_photos.patches``).

    Returns
    -------
    PhotoCharacterization
    """
    if not photographs:
        raise InputError("photographs: expected at least one photograph of the chart")
    order = list(dict.fromkeys(photograph.light for photograph in photographs))
    missing = [name for name in order if name not in lights]
    if missing:
        raise InputError(f"lights: no spectrum for {missing}")
    grid = estimation_grid(chart, {name: lights[name] for name in order})
    merged = []
    for light in order:
        group = [p for p in photographs if p.light == light]
        merged.append(
            merge_exposures(
                [
                    sample_patches(p.photo, p.corners, chart.rows, chart.columns, fraction=fraction)
                    for p in group
                ],
                [p.exposure_s for p in group],
                white_level=min(p.photo.white_level for p in group),
                floor=floor,
                source=f"the photographs under {light}",
            )
        )
    rgb = np.stack([m.rgb for m in merged])
    if np.any(rgb.mean(axis=(1, 2)) <= 0):
        dark = order[int(np.argmin(rgb.mean(axis=(1, 2))))]
        raise InputError(f"the photographs under {dark}: no signal on the chart's patches")
    reflectances = _on_grid(chart.reflectances, grid)
    light_spectra = np.concatenate([_on_grid(lights[name], grid) for name in order])
    result = estimate_response(
        np.clip(rgb, 0.0, None),
        reflectances,
        light_spectra,
        grid.wavelengths_nm,
        field_positions=chart.positions(),
        prior=prior,
        return_details=True,
    )
    residuals = fit_residuals(
        np.clip(rgb, 0.0, None), reflectances, light_spectra, grid.wavelengths_nm, result
    )
    return PhotoCharacterization(
        wavelengths_nm=grid.wavelengths_nm,
        response=result.response / np.abs(result.response).max(),
        lights=tuple(order),
        light_spectra=light_spectra,
        chart=chart,
        reflectances=reflectances,
        rgb=rgb,
        exposures_used=np.stack([m.exposures_used for m in merged]),
        residuals=residuals,
        shading=result.shading,
        specularity=result.specularity,
    )
