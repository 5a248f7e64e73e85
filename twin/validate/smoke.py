"""Smoke render: a ColorChecker under the QTH lamp seen through the LCTF bands, checked against
the closed form.

This is the short end-to-end check that the installation works: a real Mitsuba spectral render
with lamp, filter and chart spectra from ``twin.components``, compared band by band with the
analytic Lambertian radiance (``twin.render.flat_target``), written as a spectral EXR, an sRGB PNG
and a
plot.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.image import imsave

from recon.preview import spectral_to_srgb
from recon.spectra import SampledSpectra, WavelengthGrid, band_integrals, resample
from recon.spectral_exr import write_spectral_exr
from twin.components.lamps import FINE_GRID, QTHLamp, irradiance_at
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import colorchecker_reflectances
from twin.render.flat_target import analytic_band_radiance, patch_means, render_flat_target
from twin.render.spectra import rendered_spp
from twin.render.variant import activate

__all__ = ["SMOKE_TOLERANCE", "run_smoke"]

CHART_COLUMNS = 6
SMOKE_TOLERANCE = 0.03
"""Largest relative band error of a patch mean against the closed form that passes."""
PLOTTED_PATCHES = ("dark skin", "blue", "green", "red", "yellow", "white 9.5 (.05 D)")


def run_smoke(
    out_dir: Path,
    *,
    pixels_per_patch: int = 24,
    spp: int = 256,
    lamp_distance_m: float = 2.0,
    incidence_deg: float = 30.0,
    seed: int = 0,
    tolerance: float = SMOKE_TOLERANCE,
) -> dict[str, Any]:
    """Render the chart, compare with the closed form, write EXR, PNGs and ``summary.json``.

    Returns
    -------
    dict
        Variant report, render time, image size, the largest relative band error per band, the
        ``tolerance`` and the ``verdict``: ``"PASS"`` when the largest error is within it.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    report = activate()
    chart = colorchecker_reflectances(FINE_GRID, out_of_range="clamp")
    lamp = QTHLamp()
    irradiance = irradiance_at(lamp.intensity(FINE_GRID), lamp_distance_m)
    lctf = LiquidCrystalTunableFilter.varispec("VS-10")
    bands = lctf.transmission(FINE_GRID)

    started = time.perf_counter()
    image = render_flat_target(
        chart,
        irradiance,
        bands,
        columns=CHART_COLUMNS,
        pixels_per_patch=pixels_per_patch,
        patch_fill=0.8,
        incidence_deg=incidence_deg,
        spp=spp,
        seed=seed,
    )
    render_s = time.perf_counter() - started
    expected = analytic_band_radiance(chart, irradiance, bands, incidence_deg=incidence_deg)
    chart_names = chart.names or ()
    measured = patch_means(image, len(chart_names), columns=CHART_COLUMNS)
    relative_error = measured / expected - 1

    # Band integral / passband area = mean spectral radiance in the band (W m^-2 sr^-1 nm^-1).
    passband_area = band_integrals(SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size)), bands)
    band_grid = WavelengthGrid(np.array(lctf.band_centres_nm))
    spectral_image = (image / passband_area).astype(np.float32)
    write_spectral_exr(
        out_dir / "colorchecker_qth.exr",
        spectral_image,
        band_grid,
        attributes={"spectwin": "smoke render: ColorChecker, QTH lamp, VariSpec VS-10 bands"},
    )
    white = resample(irradiance, band_grid, method="box")
    imsave(
        out_dir / "colorchecker_qth.png", spectral_to_srgb(spectral_image, band_grid, white=white)
    )
    _plot_bands(
        out_dir / "band_radiance.png", band_grid.wavelengths_nm, chart_names, measured, expected
    )

    summary = {
        "variant": report.as_dict(),
        "image_px": list(image.shape[:2]),
        "bands": int(image.shape[-1]),
        "spp": rendered_spp(spp),
        "render_s": round(render_s, 3),
        "max_abs_relative_error": float(np.abs(relative_error).max()),
        "max_abs_relative_error_per_band": np.abs(relative_error).max(axis=0).round(5).tolist(),
        "tolerance": tolerance,
        "verdict": "PASS" if np.abs(relative_error).max() <= tolerance else "FAIL",
        "outputs": ["colorchecker_qth.exr", "colorchecker_qth.png", "band_radiance.png"],
    }
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def _plot_bands(
    path: Path,
    centres_nm: np.ndarray,
    names: tuple[str, ...],
    measured: np.ndarray,
    expected: np.ndarray,
) -> None:
    figure = Figure(figsize=(8, 7))
    radiance_axes, error_axes = figure.subplots(2, 1, sharex=True)
    for name in PLOTTED_PATCHES:
        index = names.index(name)
        (line,) = radiance_axes.plot(centres_nm, expected[index], label=f"{name} (analytic)")
        radiance_axes.plot(centres_nm, measured[index], "o", color=line.get_color(), ms=3)
    radiance_axes.set_ylabel("band radiance [W m$^{-2}$ sr$^{-1}$]")
    radiance_axes.set_title("Mitsuba (dots) vs closed form (lines): ColorChecker, QTH lamp, VS-10")
    radiance_axes.legend(fontsize=7)
    error_axes.plot(centres_nm, 100 * (measured / expected - 1).T, color="0.5", lw=0.7)
    error_axes.set_xlabel("LCTF band centre [nm]")
    error_axes.set_ylabel("relative error [%] (24 patches)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
