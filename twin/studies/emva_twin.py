"""A twin camera against a real EMVA 1288 measurement: the same procedure, the same analysis.

:func:`run_emva_comparison` repeats a real measurement (its exposure times, photons per pixel and
image counts) with a twin camera (:func:`twin.sensor.emva_measurement.simulate_measurement`),
analyses both data sets with the ``emva1288`` package (:mod:`recon.emva.analysis`) and sets
the figures side by side, with the photon transfer, sensitivity and linearity of both in one
figure. For a camera fitted to that measurement (``spectwin camera fit``) the figures should
agree within the scatter of the measurement itself; a figure the measurement does not resolve
(a DSNU below its detection limit) agrees only in being unresolved.

References
----------
- EMVA Standard 1288, Release 3.0 (2010): section 6 (photon transfer and sensitivity plots),
  section 8 (DSNU, PRNU).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from recon.emva.analysis import EMVAAnalysis, analyse_measurement
from recon.emva.descriptor import read_descriptor
from recon.measured_data import data_path
from twin.rigs.camera_config import load_camera_config
from twin.sensor.emva_measurement import simulate_measurement

__all__ = ["DEFAULT_DESCRIPTOR", "DEFAULT_WAVELENGTH_NM", "COMPARED", "run_emva_comparison"]

DEFAULT_DESCRIPTOR = "real/emva1288_basler_ccd12/EMVA1288_Data.txt"  # inside recon/data
DEFAULT_WAVELENGTH_NM = 550.0
COMPARED = (
    "system_gain_dn_per_e",
    "dark_noise_dn",
    "quantum_efficiency_percent",
    "saturation_capacity_photons",
    "saturation_capacity_e",
    "dsnu_e",
    "prnu_percent",
    "snr_max",
    "dynamic_range",
    "dark_current_from_mean_e_per_s",
    "linearity_error_min_percent",
    "linearity_error_max_percent",
)


def _difference_percent(real: float, twin: float) -> float:
    if not (math.isfinite(real) and math.isfinite(twin)) or real == 0:
        return math.nan
    return 100 * (twin / real - 1)


def _linearity_deviation(analysis: EMVAAnalysis) -> np.ndarray:
    """Deviation (%) of the signal from EMVA 1288's straight line through the 5-95 % range."""
    transfer = analysis.transfer
    first, last = transfer.linearity_range
    chosen = slice(first, last + 1)
    photons, signal = transfer.photons[chosen], transfer.signal_dn[chosen]
    slope, intercept = np.polyfit(photons, signal, 1, w=1 / signal)
    line = slope * transfer.photons + intercept
    return 100 * (transfer.signal_dn - line) / line


def photon_transfer_figure(real: EMVAAnalysis, twin: EMVAAnalysis, camera: str) -> Figure:
    """Photon transfer, sensitivity and linearity of the real and the twin measurement."""
    figure = Figure(figsize=(15, 4.6))
    transfer_axes, sensitivity_axes, linearity_axes = figure.subplots(1, 3)
    for analysis, label, marker, colour in ((real, "real", "o", "C0"), (twin, "twin", "x", "C1")):
        transfer = analysis.transfer
        top = transfer.sensitivity_stop + 1
        transfer_axes.plot(
            transfer.signal_dn,
            transfer.temporal_variance_dn2,
            marker,
            color=colour,
            ms=4,
            mfc="none",
            label=f"{label}: K = {analysis.system_gain_dn_per_e:.4f} DN/e-",
        )
        fit_x = transfer.signal_dn[:top]
        transfer_axes.plot(fit_x, analysis.system_gain_dn_per_e * fit_x, color=colour, lw=0.8)
        sensitivity_axes.plot(
            transfer.photons,
            transfer.signal_dn,
            marker,
            color=colour,
            ms=4,
            mfc="none",
            label=f"{label}: QE = {100 * analysis.quantum_efficiency:.1f} %",
        )
        saturation = transfer.saturation_index
        sensitivity_axes.axvline(transfer.photons[saturation], lw=0.6, ls=":", color="0.5")
        first, last = transfer.linearity_range
        linearity_axes.plot(
            transfer.photons[first : last + 1],
            _linearity_deviation(analysis)[first : last + 1],
            marker + "-",
            ms=4,
            mfc="none",
            lw=0.6,
            label=label,
        )
    transfer_axes.set_xlabel("mean signal above dark  $\\mu_y - \\mu_{y.dark}$ [DN]")
    transfer_axes.set_ylabel("temporal variance  $\\sigma^2_y - \\sigma^2_{y.dark}$ [DN$^2$]")
    transfer_axes.set_title("photon transfer")
    sensitivity_axes.set_xlabel("photons per pixel  $\\mu_p$")
    sensitivity_axes.set_ylabel("mean signal above dark [DN]")
    sensitivity_axes.set_title("sensitivity (dotted: saturation)")
    linearity_axes.axhline(0, color="0.7", lw=0.6)
    linearity_axes.set_xlabel("photons per pixel  $\\mu_p$")
    linearity_axes.set_ylabel("deviation from a straight line [%]")
    linearity_axes.set_title("linearity (5-95 % of saturation)")
    for axes in (transfer_axes, sensitivity_axes, linearity_axes):
        axes.legend(fontsize=8)
    source = real.descriptor.path
    measured = source.parent.name if source is not None else "a measurement"
    figure.suptitle(f"EMVA 1288: {camera} against {measured}")
    figure.tight_layout()
    return figure


def run_emva_comparison(
    camera: str | Path,
    out_dir: Path,
    *,
    descriptor: Path | None = None,
    wavelength_nm: float | None = None,
    seed: int = 0,
    step: Callable[[int, int], None] | None = None,
) -> dict[str, Any]:
    """Repeat a real EMVA 1288 measurement with a twin camera and compare the analyses.

    Parameters
    ----------
    camera
        A camera of ``scenes/cameras`` or a camera file.
    out_dir
        Folder for the twin's data set (``EMVA1288_Data.txt``, ``images/``),
        ``photon_transfer.png`` and ``emva_comparison.json``.
    descriptor
        The real measurement; by default the one the camera was fitted to, else the shipped
        Basler CCD measurement.
    wavelength_nm
        The light's wavelength; by default the fitted camera's, else 550 nm.
    seed
        Seed of the twin's temporal noise.
    step
        Called after every simulated frame with the frames done and their total (progress).

    Returns
    -------
    dict
        ``figures``: for each compared figure its ``real`` and ``twin`` value and their
        ``difference_percent``; the DSNU's detection limits; what was written.
    """
    config = load_camera_config(camera)
    fitted = config.emva1288
    if descriptor is None:
        descriptor = fitted.descriptor_path() if fitted else data_path(DEFAULT_DESCRIPTOR)
    if wavelength_nm is None:
        wavelength_nm = fitted.wavelength_nm if fitted else DEFAULT_WAVELENGTH_NM
    plan = read_descriptor(descriptor)
    real = analyse_measurement(plan)
    header = (
        f"{config.name} ({config.serial}): the twin's repetition of {plan.path}",
        f"at {wavelength_nm:g} nm, seed {seed} (spectwin camera --emva).",
    )
    written = simulate_measurement(
        config, plan, out_dir, wavelength_nm=wavelength_nm, seed=seed, header=header, step=step
    )
    twin = analyse_measurement(written)
    real_figures, twin_figures = real.figures(), twin.figures()
    figures = {
        key: {
            "real": real_figures[key],
            "twin": twin_figures[key],
            "difference_percent": _difference_percent(real_figures[key], twin_figures[key]),
        }
        for key in COMPARED
    }
    figure = photon_transfer_figure(real, twin, config.name)
    figure.savefig(out_dir / "photon_transfer.png", dpi=110)
    summary: dict[str, Any] = {
        "camera": config.name,
        "descriptor": str(plan.path),
        "twin_descriptor": str(written.path),
        "wavelength_nm": wavelength_nm,
        "seed": seed,
        "figures": figures,
        "dsnu_detection_limit_e": {
            "real": real.dsnu_detection_limit_e,
            "twin": twin.dsnu_detection_limit_e,
        },
        "outputs": ["EMVA1288_Data.txt", "images/", "photon_transfer.png", "emva_comparison.json"],
    }
    (out_dir / "emva_comparison.json").write_text(json.dumps(summary, indent=2))
    return summary
