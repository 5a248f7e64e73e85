"""Figures and the HTML page of ``spectwin demo`` (twin.studies.demo).

Each ``plot_*`` writes one PNG; :func:`write_report` assembles the page from the figures and the
metrics, with links to the JSON.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.preview import spectral_to_srgb
from recon.spectra import DEFAULT_GRID
from twin.components.lamps import FINE_GRID, HMILamp, QTHLamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.output_format import format_value
from twin.studies.demo_spectralization import BandSpectralization

__all__ = [
    "plot_exposure_plan",
    "plot_lamps_and_filter",
    "plot_raw_frames",
    "plot_spectralization",
    "plot_textures",
    "write_report",
]


def _save(figure: Figure, path: Path) -> Path:
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    return path


def plot_lamps_and_filter(path: Path) -> Path:
    """The HMI and QTH lamp spectra (relative) and the VS-10 LCTF's 33 passbands."""
    wavelengths = FINE_GRID.wavelengths_nm
    figure = Figure(figsize=(8, 5.5))
    lamps, bands = figure.subplots(2, 1, sharex=True)
    for lamp, name in ((HMILamp(), "HMI (Broncolor F575)"), (QTHLamp(), "QTH (3000 K)")):
        spectrum = lamp.intensity(FINE_GRID).values
        lamps.plot(wavelengths, spectrum / spectrum.max(), lw=0.8, label=name)
    lamps.set_ylabel("relative intensity")
    lamps.set_title("lamps (thesis Fig. 3.4)")
    lamps.legend(fontsize=8)
    transmission = LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID).values
    bands.plot(wavelengths, transmission.T, lw=0.7)
    bands.set_xlim(380, 740)
    bands.set_xlabel("wavelength, nm")
    bands.set_ylabel("transmission")
    bands.set_title("VariSpec VS-10 LCTF, 33 bands")
    return _save(figure, path)


def plot_exposure_plan(calibration: GonioCalibration, path: Path) -> Path:
    """The Eq. 3.4 exposure plan per band and the recovered inverse response curve."""
    figure = Figure(figsize=(11, 3.6))
    plan, curve = figure.subplots(1, 2)
    plan.bar(calibration.bands_nm, calibration.planned_exposure_s, width=7)
    plan.set_xlabel("band, nm")
    plan.set_ylabel("exposure, s")
    plan.set_title(
        f"exposure plan (Eq. 3.4, multiples of 1/15 s): "
        f"{calibration.planned_exposure_s.sum():.1f} s per pair",
        fontsize=9,
    )
    curve.plot(np.arange(calibration.inverse_response.size), calibration.inverse_response)
    curve.set_xlabel("pixel value, DN")
    curve.set_ylabel("relative exposure")
    curve.set_title("inverse response (Robertson 2003)", fontsize=9)
    return _save(figure, path)


def plot_raw_frames(capture: CaptureStore, camera: str, path: Path, count: int = 4) -> Path:
    """Raw frames of the measurement run: the white standard and sample pairs at 550 nm."""
    index = capture.index(camera)
    frames = capture.frames(camera)
    near_550 = np.abs(index["band_nm"] - 550.0) < 1.0
    white = np.flatnonzero((index["kind"] == "white") & near_550)[:1]
    samples = np.flatnonzero((index["kind"] == "sample") & near_550)
    chosen = np.concatenate([white, samples[:: max(len(samples) // (count - 1), 1)]])[:count]
    figure = Figure(figsize=(3.2 * len(chosen), 3.4))
    axes = figure.subplots(1, len(chosen))
    for axis, step in zip(np.atleast_1d(axes), chosen, strict=True):
        shown = axis.imshow(frames[step], cmap="gray")
        axis.set_title(
            f"{index['kind'][step]} view {index['view_id'][step]}, "
            f"{index['exposure_s'][step]:.2f} s",
            fontsize=8,
        )
        axis.axis("off")
        figure.colorbar(shown, ax=axis, fraction=0.046, label="DN")
    figure.suptitle("raw CCD frames at 550 nm (12-bit K4 behind the LCTF)", fontsize=9)
    return _save(figure, path)


def plot_textures(btf: BTFStore, path: Path, count: int = 6) -> Path:
    """Registered textures of ``count`` pairs as sRGB under D65 (reflectance x pi)."""
    pairs = np.linspace(0, btf.shape[0] - 1, min(count, btf.shape[0])).astype(int)
    figure = Figure(figsize=(2.6 * len(pairs), 2.9))
    axes = figure.subplots(1, len(pairs))
    for axis, pair in zip(np.atleast_1d(axes), pairs, strict=True):
        texture = np.pi * btf.read_pair(int(pair))
        axis.imshow(spectral_to_srgb(np.clip(texture, 0, None), btf.grid))
        light, view = btf.light_dirs[pair], btf.view_dirs[pair]
        axis.set_title(f"pair {pair}: light z {light[2]:.2f}, view z {view[2]:.2f}", fontsize=8)
        axis.axis("off")
    figure.suptitle("registered textures of the BTF (sRGB preview)", fontsize=9)
    return _save(figure, path)


def plot_spectralization(result: BandSpectralization, path: Path) -> Path:
    """Reconstructed versus true spectra at three texels, the error map and its histogram."""
    wavelengths = DEFAULT_GRID.wavelengths_nm
    figure = Figure(figsize=(13, 3.6))
    spectra, error_map, histogram = figure.subplots(1, 3)
    height, width = result.truth.shape[:2]
    for (y, x), colour in zip(
        ((height // 4, width // 4), (height // 2, width // 2), (3 * height // 4, width // 3)),
        ("C0", "C1", "C2"),
        strict=True,
    ):
        spectra.plot(wavelengths, result.truth[y, x], color=colour, lw=2, label=f"truth ({y},{x})")
        spectra.plot(wavelengths, result.cube[y, x], "--", color=colour, label="reconstructed")
        spectra.plot(
            wavelengths[result.bands], result.band_values[y, x], ".", color=colour, alpha=0.6
        )
    spectra.set_xlabel("wavelength, nm")
    spectra.set_ylabel("reflectance factor")
    spectra.set_title("RGB + noisy bands (dots) -> spectra", fontsize=9)
    spectra.legend(fontsize=6)
    shown = error_map.imshow(result.relative_error_pct, cmap="magma", vmin=0)
    error_map.set_title(
        f"relative error (Eq. 6.8): mean {result.relative_error_pct.mean():.2f} %", fontsize=9
    )
    error_map.axis("off")
    figure.colorbar(shown, ax=error_map, fraction=0.046, label="%")
    histogram.hist(result.delta_e94.ravel(), bins=40)
    histogram.set_xlabel("Delta E94 (10 CIE illuminants)")
    histogram.set_ylabel("texels")
    histogram.set_title(f"mean Delta E94 {result.delta_e94.mean():.2f}", fontsize=9)
    return _save(figure, path)


_SECTIONS = (
    ("lamps_filter.png", "Lamps and filter", "The gonioreflectometer's light and filter."),
    ("exposure_plan.png", "Calibration", "Exposure plan and camera response."),
    ("raw_frames.png", "Raw frames", "What the virtual CCD recorded."),
    ("textures.png", "Registered textures", "BTF after calibration and registration."),
    ("evaluation.png", "BTF versus the twin's truth", "Field spectra and error histogram."),
    ("spectralization.png", "Spectralization", "RGB plus noisy band images (chapter 10)."),
    (
        "validation/figure46.png",
        "Figure 4.6",
        "Photograph, spectral and RGB renderings; Delta E94 on the matte fields. With the "
        "demo's 5 directions the glossy fields' highlights spread into white patches.",
    ),
    ("validation/spectrophotometer_45_0.png", "45/0 comparison", "Figures 4.3/4.4."),
)


def write_report(out: Path, metrics: dict) -> Path:
    """``report.html`` in ``out``: the headline numbers, then every figure that exists."""
    rows = "".join(
        f"<tr><td>{html.escape(str(key))}</td><td>{html.escape(format_value(value))}</td></tr>"
        for key, value in metrics["headline"].items()
    )
    sections = "".join(
        f"<h2>{html.escape(title)}</h2><p>{html.escape(caption)}</p>"
        f'<img src="{html.escape(name)}" alt="{html.escape(title)}" style="max-width:100%">'
        for name, title, caption in _SECTIONS
        if (out / name).exists()
    )
    page = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>spectwin demo</title>"
        "<style>body{font-family:sans-serif;max-width:1400px;margin:auto}"
        "td{padding:2px 10px;border-bottom:1px solid #ddd}</style></head><body>"
        "<h1>spectwin demo: gonio capture to validated spectral BTF</h1>"
        f"<p>{html.escape(metrics['description'])}</p>"
        f"<table>{rows}</table>"
        '<p>All numbers: <a href="metrics.json">metrics.json</a>.</p>'
        f"{sections}</body></html>"
    )
    path = out / "report.html"
    path.write_text(page)
    return path
