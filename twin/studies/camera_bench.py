"""A virtual bench test of one camera: photon transfer, dark frames and HMI flicker, as figures.

What a rig builder checks before buying: where the camera saturates and how noisy it is (photon
transfer, EMVA 1288), what its dark frames look like at long exposure (thesis 3.3 and
Fig. 10.2d), and how much the HMI lamp's 15 Hz line flicker (thesis 3.2.2) spreads frames of a
white target in the 550 nm LCTF band for each exposure time (monochrome cameras whose exposure
range covers the sweep, 20 to 300 ms).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from twin.components.lamps import FINE_GRID, HMILamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.sensor.model import Sensor
from twin.sensor.white_reference import white_reference_rates

__all__ = ["run_camera_report"]

_WAVELENGTH_NM = 550.0
_READOUT_S = 0.130  # filter switching and image download per frame (thesis 4.1.1)
_FLICKER_EXPOSURES_S = (0.02, 0.3)  # the sweep, around the multiples of 1/15 s


def _photon_transfer(sensor: Sensor, rng: np.random.Generator, exposure_s: float) -> dict:
    shape = (sensor.height, sensor.width) + ((3,) if sensor.is_colour else ())
    levels_e = np.linspace(0.0, 1.1, 45) * sensor.saturation_capacity_e
    pair_means, pair_variances = [], []
    for level in levels_e:
        first, second = (
            sensor.capture(np.full(shape, level, np.float32), exposure_s, rng).astype(np.float64)
            for _ in range(2)
        )
        pair_means.append((first.mean() + second.mean()) / 2)
        pair_variances.append(np.var(first - second) / 2)
    means, variances = np.array(pair_means), np.array(pair_variances)
    dark_mean, dark_variance = means[0], variances[0]
    linear = (levels_e > 0) & (levels_e < 0.7 * sensor.saturation_capacity_e)
    gain = np.polyfit(means[linear] - dark_mean, variances[linear] - dark_variance, 1)[0]
    return {
        "levels_e": levels_e,
        "mean_dn": means,
        "variance_dn2": variances,
        "gain_dn_per_e": float(gain),
        "dark_noise_dn": float(math.sqrt(dark_variance)),
    }


def _flicker_sweep(sensor: Sensor, rng: np.random.Generator) -> dict:
    lamp = HMILamp()
    band = LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)
    band = band.row(f"lctf_{_WAVELENGTH_NM:g}nm")
    exposures_s = np.union1d(
        np.linspace(*_FLICKER_EXPOSURES_S, 57), np.arange(1, 5) / lamp.flicker_hz
    )
    # Place the white target so that the longest exposure fills 60 % of saturation.
    rates_at_1m = white_reference_rates(sensor, lamp, band, distance_m=1.0)[:, 0]
    fill = 0.6 * sensor.saturation_capacity_e / (rates_at_1m.sum() * exposures_s.max())
    rates = rates_at_1m * fill
    predicted, simulated = [], []
    for exposure_s in exposures_s:
        starts = np.arange(40) * (exposure_s + _READOUT_S)
        electrons = np.array([lamp.part_exposure_s(t0, exposure_s) @ rates for t0 in starts])
        predicted.append(np.std(electrons, ddof=1) / electrons.mean())
        frame_means = [
            sensor.capture(
                np.full((sensor.height, sensor.width), mean, np.float32), exposure_s, rng
            ).mean()
            - sensor.config.adc_offset_dn
            for mean in electrons
        ]
        simulated.append(np.std(frame_means, ddof=1) / np.mean(frame_means))
    return {
        "exposures_s": exposures_s,
        "predicted_relative_spread": np.array(predicted),
        "simulated_relative_spread": np.array(simulated),
    }


def run_camera_report(
    camera: str, out_dir: Path, *, roi: int = 64, seed: int = 0
) -> dict[str, Any]:
    """Simulate the bench test of ``camera``; write ``camera_report.png`` and ``summary.json``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    sensor = Sensor(camera, roi=(roi, roi))
    rng = np.random.default_rng(seed)
    short_s = sensor.config.exposure_range_s[0] * 10
    transfer = _photon_transfer(sensor, rng, short_s)
    long_s = min(300.0, sensor.config.exposure_range_s[1])
    dark = Sensor(camera).mean_dark_electrons(long_s)

    low, high = sensor.config.exposure_range_s
    sweep_flicker = (
        not sensor.is_colour and low <= _FLICKER_EXPOSURES_S[0] <= _FLICKER_EXPOSURES_S[1] <= high
    )
    figure = Figure(figsize=(15 if sweep_flicker else 10, 4.5))
    axes = figure.subplots(1, 3 if sweep_flicker else 2)
    axes[0].plot(transfer["mean_dn"] - transfer["mean_dn"][0], transfer["variance_dn2"], ".")
    axes[0].set_xlabel("mean signal above dark [DN]")
    axes[0].set_ylabel("temporal variance [DN$^2$]")
    axes[0].set_title(f"photon transfer: K = {transfer['gain_dn_per_e']:.3f} DN/e$^-$")
    shown = axes[1].imshow(dark, cmap="magma", vmax=np.percentile(dark, 99.5))
    axes[1].set_title(f"mean dark electrons, {long_s:g} s (full sensor)")
    figure.colorbar(shown, ax=axes[1])
    summary: dict[str, Any] = {
        "camera": sensor.config.name,
        "roi_px": roi,
        "seed": seed,
        "measured_gain_dn_per_e": round(transfer["gain_dn_per_e"], 4),
        "configured_gain_dn_per_e": sensor.config.system_gain_dn_per_e,
        "measured_dark_noise_dn": round(transfer["dark_noise_dn"], 3),
        "configured_read_noise_dn": sensor.config.read_noise_dn,
        "saturation_capacity_e": round(sensor.saturation_capacity_e, 1),
        "dark_current_e_per_s": sensor.dark_current_e_per_s,
        "outputs": ["camera_report.png", "summary.json"],
    }
    if not sensor.is_colour and not sweep_flicker:
        summary["flicker"] = (
            f"not simulated: the sweep needs {_FLICKER_EXPOSURES_S[0]:g} to "
            f"{_FLICKER_EXPOSURES_S[1]:g} s exposures, the camera takes {low:g} to {high:g} s"
        )
    if sweep_flicker:
        flicker = _flicker_sweep(Sensor(camera, roi=(32, 32)), rng)
        exposures_ms = 1000 * flicker["exposures_s"]
        axes[2].plot(exposures_ms, 100 * flicker["predicted_relative_spread"], label="lamp model")
        axes[2].plot(exposures_ms, 100 * flicker["simulated_relative_spread"], ".", label="frames")
        for multiple in range(1, 5):
            axes[2].axvline(1000 * multiple / 15, color="0.8", lw=0.8)
        axes[2].set_xlabel("exposure time [ms] (grey: multiples of 1/15 s)")
        axes[2].set_ylabel("frame-to-frame spread [%]")
        axes[2].set_title("HMI flicker, white target, 550 nm band")
        axes[2].legend()
        at_period = np.argmin(np.abs(flicker["exposures_s"] - 1 / 15))
        summary["flicker_spread_percent_at_50ms"] = round(
            100
            * float(np.interp(0.05, flicker["exposures_s"], flicker["simulated_relative_spread"])),
            3,
        )
        summary["flicker_spread_percent_near_66_7ms"] = round(
            100 * float(flicker["simulated_relative_spread"][at_period]), 3
        )
    figure.suptitle(f"{sensor.config.name} ({sensor.config.serial})")
    figure.tight_layout()
    figure.savefig(out_dir / "camera_report.png", dpi=110)
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
