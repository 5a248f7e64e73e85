"""The thesis's chapter 7 study, run on twin-made textures and on a real multispectral image.

Textures: the noise-free reflectance of ground-truth materials (``twin.render.truth.truth_btf`` at
one
light and view direction, times :math:`\\pi` so a white Lambertian surface reads 1, as
reflectance factors do for Eq. 6.8's :math:`\\epsilon = 10^{-3}`). Camera: the Nikon D70 response
under CIE D65 (the thesis's SVS Vistek stand-in, ``scenes/cameras/svs_vistek_4022.yaml``). Real
image: the llanos2019 seven-band image with its own camera (``recon.measured_data``).

Outputs: ``study.json`` and PNGs: mean errors per method for whisk-broom and push-broom data,
relative error maps, example spectra, the spot-count sweep (Fig. 7.9), the noise sweep
(Fig. 7.10) and the incomplete-information maps (section 7.6).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from recon.errors import InputError
from recon.experiments.sampling import exclude_region, push_broom_mask, whisk_broom_mask
from recon.experiments.sparse import (
    METHODS,
    ProtocolResult,
    noise_sweep,
    run_protocol,
    spot_count_sweep,
)
from recon.measured_data import read_llanos2019_multispectral
from recon.spectra import DEFAULT_GRID
from twin.components.detectors import rgb_camera_response
from twin.components.lamps import cie_illuminant
from twin.render.truth import texture_truth

__all__ = ["STUDY_LIGHT", "STUDY_VIEW", "run_study", "study_response", "twin_texture"]

_SWEPT = ("spectralization", "spectralization p_dyn=1", "hardeberg", "dong", "murakami")
STUDY_LIGHT = np.array([[np.sin(np.radians(15.0)), 0.0, np.cos(np.radians(15.0))]])
STUDY_VIEW = np.array([[0.0, 0.0, 1.0]])


def twin_texture(material: str, *, texels: int = 96, spp: int = 64) -> np.ndarray:
    """Reflectance factors ``(texels, texels, 33)`` of a twin material, lit 15 degrees off
    the normal and seen from above, each texel fitted with the material's part reflectances
    (:func:`twin.render.truth.texture_truth` without the flat surface spectrum: no highlight
    reaches the view from this light)."""
    truth = texture_truth(material, STUDY_LIGHT, STUDY_VIEW, texels=texels, spp=spp, surface=False)
    return truth.reflectance[0]


def study_response() -> np.ndarray:
    """:math:`R_{cam}` ``(33, 3)``: Nikon D70 response times CIE D65 on the default grid,
    scaled so that a perfect white gives 1 in its largest channel."""
    camera = rgb_camera_response("Nikon D70", DEFAULT_GRID).values.T
    light = cie_illuminant("D65", DEFAULT_GRID).values
    response = camera * light[:, None]
    return response / (np.ones(DEFAULT_GRID.size) @ response).max()


def _chroma_region(truth: np.ndarray, response: np.ndarray, percentile: float = 80) -> np.ndarray:
    """The most colourful pixels (largest RGB chroma): the stripes of section 7.6."""
    rgb = truth @ response
    chroma = rgb.max(axis=-1) - rgb.min(axis=-1)
    return chroma >= np.percentile(chroma, percentile)


def _bars(results: dict[str, ProtocolResult], title: str, path: Path) -> None:
    figure = Figure(figsize=(7, 3.5))
    axes = figure.subplots()
    names = list(next(iter(results.values())).mean_errors)
    width = 0.8 / len(results)
    for index, (label, result) in enumerate(results.items()):
        values = [result.mean_errors[name] for name in names]
        axes.bar(np.arange(len(names)) + index * width, values, width, label=label)
    axes.set_xticks(np.arange(len(names)) + 0.4 - width / 2, names, rotation=20)
    axes.set_ylabel("mean relative error (Eq. 6.8), %")
    axes.set_yscale("log")
    axes.set_title(title)
    axes.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _maps(result: ProtocolResult, title: str, path: Path, limit: float = 20.0) -> None:
    names = list(result.error_maps)
    figure = Figure(figsize=(2.3 * len(names), 2.6))
    axes = figure.subplots(1, len(names))
    for axis, name in zip(np.atleast_1d(axes), names, strict=True):
        image = axis.imshow(result.error_maps[name], vmin=0, vmax=limit, cmap="magma")
        axis.set_title(f"{name}\n{result.mean_errors[name]:.2f} %", fontsize=8)
        axis.axis("off")
    figure.colorbar(image, ax=axes, shrink=0.8, label="relative error, %")
    figure.suptitle(title, fontsize=9)
    figure.savefig(path, dpi=110)


def _spectra(
    truth: np.ndarray, result: ProtocolResult, wavelengths: np.ndarray, title: str, path: Path
) -> None:
    """The truth and every estimate at the brighter-than-median pixel where Hardeberg errs
    most (section 7.1: where a 3-D subspace fails)."""
    brightness = truth.mean(axis=-1)
    errors = np.where(brightness >= np.median(brightness), result.error_maps["hardeberg"], -1.0)
    worst = np.unravel_index(np.argmax(errors), truth.shape[:2])
    figure = Figure(figsize=(5, 3.2))
    axes = figure.subplots()
    axes.plot(wavelengths, truth[worst], "k", lw=2.5, label="truth")
    for name, estimate in result.estimates.items():
        axes.plot(wavelengths, estimate[worst], lw=1, label=name)
    axes.set_xlabel("wavelength, nm")
    axes.set_ylabel("reflectance")
    axes.set_title(f"{title}: pixel {worst}", fontsize=9)
    axes.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _sweep(curves: dict, x: list, xlabel: str, title: str, path: Path) -> None:
    figure = Figure(figsize=(5, 3.2))
    axes = figure.subplots()
    for name, values in curves.items():
        axes.plot(x, values, "o-", label=name)
    axes.set_xlabel(xlabel)
    axes.set_ylabel("mean relative error, %")
    axes.set_title(title, fontsize=9)
    axes.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _study_case(
    name: str,
    truth: np.ndarray,
    response: np.ndarray,
    wavelengths: np.ndarray,
    out_dir: Path,
    sweeps: bool,
    methods: tuple[str, ...],
) -> dict[str, Any]:
    shape = truth.shape[:2]
    whisk = run_protocol(truth, response, whisk_broom_mask(shape), methods=methods)
    push = run_protocol(truth, response, push_broom_mask(shape), methods=methods)
    _bars(
        {"whisk-broom 250 spots": whisk, "push-broom 2 lines": push},
        name,
        out_dir / f"{name}_errors.png",
    )
    _maps(whisk, f"{name}: whisk-broom, 250 spots, 1 % RGB noise", out_dir / f"{name}_maps.png")
    _spectra(truth, whisk, wavelengths, name, out_dir / f"{name}_spectra.png")
    summary: dict[str, Any] = {
        "shape": list(truth.shape),
        "whisk_broom": whisk.mean_errors,
        "push_broom": push.mean_errors,
    }
    if sweeps:
        counts = [25, 50, 100, 250, 500, 1000]
        fractions = [0.005, 0.01, 0.02, 0.03, 0.05]
        spots = spot_count_sweep(truth, response, counts=counts, methods=_SWEPT)
        noise = noise_sweep(truth, response, noise_fractions=fractions, methods=_SWEPT)
        _sweep(
            spots, counts, "whisk-broom spots", f"{name} (Fig. 7.9)", out_dir / f"{name}_spots.png"
        )
        percent = [100 * f for f in fractions]
        _sweep(
            noise,
            percent,
            "RGB noise, % of mean",
            f"{name} (Fig. 7.10)",
            out_dir / f"{name}_noise.png",
        )
        mask = whisk_broom_mask(shape)
        region = _chroma_region(truth, response)
        incomplete = run_protocol(
            truth, response, exclude_region(mask, region), methods=("spectralization", "murakami")
        )
        _maps(
            incomplete,
            f"{name}: no spectra on the most colourful 20 %",
            out_dir / f"{name}_incomplete.png",
        )
        summary |= {
            "spot_counts": counts,
            "spot_sweep": spots,
            "noise_fractions": fractions,
            "noise_sweep": noise,
            "incomplete": {
                "all_pixels": incomplete.mean_errors,
                "in_region": {
                    k: float(np.mean(v[region])) for k, v in incomplete.error_maps.items()
                },
            },
        }
    return summary


def run_study(
    out_dir: Path,
    *,
    texels: int = 96,
    materials: tuple[str, ...] = ("red_fabric", "wallpaper", "lego"),
    sweeps: bool = True,
    methods: tuple[str, ...] = tuple(METHODS),
) -> dict[str, Any]:
    """Run the chapter 7 protocols on twin textures and the llanos2019 image; write figures.

    ``methods`` are the contenders of the whisk- and push-broom protocols (names of
    :data:`recon.experiments.sparse.METHODS`, all by default; the example spectra need
    ``"hardeberg"``). The sweeps keep their own set.
    """
    if "hardeberg" not in methods:
        raise InputError(f"methods: expected 'hardeberg' among them, got {list(methods)}")
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    response = study_response()
    summary: dict[str, Any] = {"camera": "Nikon D70 x D65", "cases": {}}
    for index, material in enumerate(materials):
        truth = twin_texture(material, texels=texels)
        summary["cases"][material] = _study_case(
            material,
            truth,
            response,
            DEFAULT_GRID.wavelengths_nm,
            out_dir,
            sweeps and index == 0,
            methods,
        )
    real = read_llanos2019_multispectral()
    summary["cases"]["llanos2019"] = _study_case(
        "llanos2019", real.image, real.response, real.wavelengths_nm, out_dir, sweeps, methods
    )
    summary["seconds"] = round(time.perf_counter() - started, 1)
    (out_dir / "study.json").write_text(json.dumps(summary, indent=2))
    return summary
