"""``spectwin camchar``: a camera characterized from real chart photographs, written out.

The estimate is ``recon.chart_photos.characterize_photographs`` (thesis chapter 9); this module
writes what a user needs from it:

- ``response.csv``: ``wavelength_nm,R,G,B``, the relative response (largest value one), the
  layout of the measured cameras in ``recon/data/spectra/cameras_rawtoaces``;
- ``patches.csv``: per light and patch, the merged device RGB, the exposures merged, the
  shading and specularity of Eq. 9.7 and the fit's residuals in % of the photograph's mean;
- ``response.png``: the response (with the measured one, if given) and the residuals per patch;
- ``summary.json``: the inputs, the grid, the residuals' size and, with a measured response, the
  errors against it.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path
from typing import Any

import numpy as np

from recon.chart_photos.characterize import PhotoCharacterization
from recon.chart_photos.spectra_files import split_column
from recon.chart_photos.truth import MeasuredResponse, truth_errors, truth_on_grid
from twin.output_format import dumps
from twin.studies.camchar_figures import photo_characterization_figure

__all__ = ["write_characterization"]

OUTPUTS = ("response.csv", "patches.csv", "response.png", "summary.json")


def _write_response(path: Path, result: PhotoCharacterization) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["wavelength_nm", "R", "G", "B"])
        for wavelength, row in zip(result.wavelengths_nm, result.response, strict=True):
            writer.writerow([f"{wavelength:g}", *(f"{value:.6g}" for value in row)])


def _write_patches(path: Path, result: PhotoCharacterization) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(
            [
                "light",
                "patch",
                "name",
                *(f"rgb_{c}" for c in "RGB"),
                *(f"exposures_{c}" for c in "RGB"),
                "shading",
                "specularity",
                *(f"residual_{c}_pct" for c in "RGB"),
            ]
        )
        for photo, light in enumerate(result.lights):
            for patch, name in enumerate(result.chart.patch_names):
                writer.writerow(
                    [
                        light,
                        patch + 1,
                        name,
                        *(f"{v:.6g}" for v in result.rgb[photo, patch]),
                        *(int(v) for v in result.exposures_used[photo, patch]),
                        f"{result.shading[photo, patch]:.4f}",
                        f"{result.specularity[photo, patch]:.4f}",
                        *(f"{100 * v:.3f}" for v in result.residuals[photo, patch]),
                    ]
                )


def _short(light: str) -> str:
    """A light as a legend names it: the column of ``FILE:COLUMN``, the name of a file."""
    path, column = split_column(light)
    return column if column is not None else path.name


def _drawn(
    result: PhotoCharacterization, truth: MeasuredResponse | None
) -> tuple[str, np.ndarray] | None:
    """The measured curves to draw with the estimate, if any."""
    curves = None if truth is None else truth_on_grid(result, truth)
    return None if curves is None or truth is None else (Path(truth.source).name, curves)


def write_characterization(
    result: PhotoCharacterization,
    out_dir: Path,
    *,
    inputs: dict[str, Any],
    truth: MeasuredResponse | None = None,
    seconds: float | None = None,
) -> dict[str, Any]:
    """Write the outputs of the module description into ``out_dir``; return the summary.

    Parameters
    ----------
    result
        The characterization.
    out_dir
        The folder (made if missing).
    inputs
        What was given (photographs, chart, lights, ...), recorded as it is in the summary.
    truth
        A measured response, if given: compared with the estimate
        (``recon.chart_photos.truth``) and, as curves, drawn with it.
    seconds
        The time the characterization took.
    """
    started = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    _write_response(out_dir / "response.csv", result)
    _write_patches(out_dir / "patches.csv", result)
    residual_pct = 100 * np.abs(result.residuals)
    worst = np.unravel_index(np.argmax(residual_pct), residual_pct.shape)
    photo_characterization_figure(
        result.wavelengths_nm,
        result.response,
        _drawn(result, truth),
        residual_pct.max(axis=2),
        [_short(light) for light in result.lights],
        result.chart.patch_names,
    ).savefig(out_dir / "response.png", dpi=110)
    summary: dict[str, Any] = {
        **inputs,
        "photographs_merged_per_light": {
            light: int(result.exposures_used[index].max())
            for index, light in enumerate(result.lights)
        },
        "patches": result.chart.size,
        "grid_nm": [float(result.wavelengths_nm[0]), float(result.wavelengths_nm[-1]), 10.0],
        "peak_nm": {
            c: float(result.wavelengths_nm[np.argmax(result.response[:, i])])
            for i, c in enumerate("RGB")
        },
        "residual_rms_pct": float(np.sqrt(np.mean(residual_pct**2))),
        "residual_max_pct": float(residual_pct.max()),
        "residual_max_at": f"{_short(result.lights[worst[0]])}, patch {worst[1] + 1} "
        f"({result.chart.patch_names[worst[1]]}), {'RGB'[worst[2]]}",
    }
    if truth is not None:
        errors = truth_errors(result, truth)
        summary["truth"] = truth.source
        summary["truth_range_nm"] = list(errors.range_nm)
        if errors.curve_pct is not None:
            summary["truth_curve_rmse_pct"] = errors.curve_pct.tolist()
            summary["truth_curve_worst_pct"] = float(errors.curve_pct.max())
        summary["truth_per_light_rmse_pct"] = errors.per_light_pct.tolist()
        summary["truth_per_light_worst_pct"] = float(errors.per_light_pct.max())
    summary["seconds"] = round((seconds or 0.0) + time.perf_counter() - started, 2)
    summary["outputs"] = list(OUTPUTS)
    (out_dir / "summary.json").write_text(dumps(summary))
    return summary
