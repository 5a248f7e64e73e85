"""Figures of camera characterization: estimated against true response curves, the errors of
several methods across cameras, and a characterization from real photographs with its fit's
residuals per patch."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

__all__ = ["errors_figure", "photo_characterization_figure", "response_curves_figure"]

_CHANNEL_COLOURS = ("tab:red", "tab:green", "tab:blue")
_STYLES = ("-", "--", ":", "-.")


def response_curves_figure(
    wavelengths: np.ndarray,
    truth: np.ndarray,
    estimates: Mapping[str, np.ndarray],
    title: str,
) -> Figure:
    """The true response ``(K, 3)`` (wide, pale) and each estimate after one global scale (the
    least-squares factor onto the truth), all relative to the true peak; one line style per
    estimate, named in the legend."""
    figure = Figure(figsize=(8, 4.5))
    axes = figure.subplots()
    peak = np.abs(truth).max()
    for channel, colour_name in enumerate(_CHANNEL_COLOURS):
        axes.plot(
            wavelengths,
            truth[:, channel] / peak,
            color=colour_name,
            lw=3,
            alpha=0.35,
            label="truth" if channel == 0 else None,
        )
        for (label, estimate), style in zip(estimates.items(), _STYLES, strict=False):
            scale = np.sum(estimate * truth) / np.sum(estimate * estimate)
            axes.plot(
                wavelengths,
                scale * estimate[:, channel] / peak,
                style,
                color=colour_name,
                lw=1.2,
                label=label if channel == 0 else None,
            )
    axes.set_xlabel("wavelength [nm]")
    axes.set_ylabel("relative response")
    axes.set_title(title)
    axes.legend(fontsize=8)
    figure.tight_layout()
    return figure


def errors_figure(
    cameras: list[str],
    errors_pct: Mapping[str, np.ndarray],
    title: str,
    *,
    bounds_pct: Mapping[str, float] | None = None,
) -> Figure:
    """One marker per camera and method (errors in percent), cameras sorted by the first
    method's error; a dashed line at each of ``bounds_pct`` (label -> value)."""
    first = next(iter(errors_pct.values()))
    order = np.argsort(first)
    figure = Figure(figsize=(12, 5))
    axes = figure.subplots()
    positions = np.arange(len(cameras))
    for (label, errors), marker in zip(errors_pct.items(), "o^sD", strict=False):
        axes.plot(positions, np.asarray(errors)[order], marker, ms=5, label=label)
    for (label, bound), style in zip((bounds_pct or {}).items(), ("--", ":"), strict=False):
        axes.axhline(bound, color="grey", lw=0.8, ls=style, label=label)
    axes.set_ylim(bottom=0)
    axes.set_xticks(positions, [cameras[i] for i in order], rotation=90, fontsize=7)
    axes.set_ylabel("worst channel's RMSE [% of peak]")
    axes.set_title(title)
    axes.legend(fontsize=8, ncol=3, loc="upper center")
    figure.tight_layout()
    return figure


def photo_characterization_figure(
    wavelengths: np.ndarray,
    response: np.ndarray,
    truth: tuple[str, np.ndarray] | None,
    residual_pct: np.ndarray,
    lights: Sequence[str],
    patch_names: Sequence[str],
) -> Figure:
    """Left: the estimated response ``(K, 3)`` (largest value one) and, if given, a measured one
    ``(name, (K, 3))`` (NaN where not measured) after one global scale onto the estimate. Right:
    the largest residual of the fit per patch ``(P, J)`` in percent, one row of bars per light."""
    figure = Figure(figsize=(13, 4.8))
    curves, bars = figure.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    for channel, colour_name in enumerate(_CHANNEL_COLOURS):
        curves.plot(
            wavelengths,
            response[:, channel],
            color=colour_name,
            lw=1.5,
            label="estimate" if channel == 0 else None,
        )
    if truth is not None:
        name, measured = truth
        known = np.isfinite(measured)
        scale = np.sum(measured[known] * response[known]) / np.sum(measured[known] ** 2)
        for channel, colour_name in enumerate(_CHANNEL_COLOURS):
            curves.plot(
                wavelengths,
                scale * measured[:, channel],
                color=colour_name,
                lw=3,
                alpha=0.35,
                label=f"measured ({name})" if channel == 0 else None,
            )
    curves.set_xlabel("wavelength [nm]")
    curves.set_ylabel("relative response")
    curves.set_title("spectral response")
    curves.legend(fontsize=8)
    positions = np.arange(len(patch_names))
    width = 0.8 / max(len(lights), 1)
    for index, light in enumerate(lights):
        bars.bar(positions + index * width, residual_pct[index], width, label=light)
    bars.set_xticks(positions + 0.4 - width / 2, patch_names, rotation=90, fontsize=6)
    bars.set_ylabel("largest channel residual [% of mean RGB]")
    bars.set_title("fit residuals per patch (Eq. 9.7)")
    if len(lights) <= 12:
        bars.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), title="light")
    figure.tight_layout()
    return figure
