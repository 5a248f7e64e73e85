"""``spectwin spectralize`` measured: a real image against the truth and the peers, and the time
at a megapixel. Prints JSON.

1. Llanos's real seven-band image (342 x 408, ``recon.measured_data``) made RGB with its own
   Flea3 response, spots at 1 % of the pixels (single pixels on a regular grid), no noise:
   the mean relative error (Eq. 6.8, %) against the true seven bands of the pixels that are not
   spots, for ``recon.image_spectralization.spectralize_image`` (prior and kriging weight by
   three-fold cross-validation, hierarchical and of every pixel; ``fast``, the same two),
   Murakami 2007 and A+ (``recon.baselines``), with the seconds of each; and the cost of the
   cross-validated path over the plain solve.
2. The same at 1000 x 1000 pixels: a mosaic of the real VHREL clothes reflectances (33 bands,
   ``recon.experiments.real_images``) under a measured camera and D65, spots at 1 %: seconds of
   the plain solve (``fast``: hierarchical, ``recon.spectralize.hierarchy``; and of every
   pixel), of the cross-validated path (by default in a central window of the image,
   ``recon.image_spectralization.window``, and hierarchical in RGBXY), of that path solving
   every pixel, in a window of 250 000 px, over the whole image and with the RGBXY space given
   (not chosen against the learned one), run back to back, and their ratios; also the
   process's CPU seconds of each, which a machine shared with other jobs disturbs less than
   the wall time.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.spectralize_image [--side 1000]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

from benchmarks.common import machine_description
from recon import baselines
from recon.experiments.real_images import real_test_image
from recon.experiments.sampling import whisk_broom_mask
from recon.image_spectralization.run import spectralize_image
from recon.image_spectralization.spots import SpotSpectra
from recon.image_spectralization.window import CROSS_VALIDATION_PIXELS
from recon.measured_data import read_llanos2019_multispectral
from recon.metrics import relative_error
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid
from recon.spectralize.hierarchy import SAMPLE_STRIDE


def _spots(truth: np.ndarray, grid: WavelengthGrid) -> tuple[SpotSpectra, np.ndarray]:
    height, width = truth.shape[:2]
    mask = whisk_broom_mask(
        (height, width), n_spots=int(round(0.01 * height * width)), spot_fraction=1e-3
    )
    rows, cols = np.nonzero(mask)
    spectra = SampledSpectra(grid, truth[rows, cols])
    return SpotSpectra(np.stack([cols, rows], axis=1), spectra, "benchmark"), mask


def _timed(function):
    started = time.perf_counter()
    value = function()
    return value, round(time.perf_counter() - started, 2)


def _ours(
    rgb, spots, response, fast, appearance="auto", window=CROSS_VALIDATION_PIXELS, stride=None
):
    return spectralize_image(
        rgb,
        spots,
        response,
        fast=fast,
        appearance=appearance,
        sample_stride=SAMPLE_STRIDE if stride is None else stride,
        cross_validation_pixels=window,
    )


def llanos_case() -> dict:
    real = read_llanos2019_multispectral()
    truth, grid = real.image, real.grid
    rgb = truth @ real.response
    spots, mask = _spots(truth, grid)
    response = SampledSpectra(grid, real.sensor_map.T, ("R", "G", "B"))
    pixels = np.flatnonzero(mask)
    rows, cols = np.nonzero(mask)
    known = truth[rows, cols]
    runs = {}  # the spectralize results, kept for their choices
    methods = {
        "spectralize (cross-validated prior)": lambda: (
            runs.setdefault("chosen", _ours(rgb, spots, response, False)).cube
        ),
        "spectralize --fast": lambda: _ours(rgb, spots, response, True).cube,
        "spectralize --fast, every pixel": lambda: _ours(rgb, spots, response, True, stride=1).cube,
        "spectralize, every pixel": lambda: _ours(rgb, spots, response, False, stride=1).cube,
        "murakami": lambda: baselines.recover(
            rgb, real.response, method="murakami", known_pixels=pixels, known_spectra=known
        ),
        "a_plus": lambda: baselines.recover(
            rgb,
            None,
            method="a_plus",
            known_pixels=pixels,
            known_spectra=known,
            sparsity=min(8, truth.shape[-1]),
        ),
    }
    errors, seconds = {}, {}
    for name, method in methods.items():
        estimate, seconds[name] = _timed(method)
        errors[name] = round(float(relative_error(estimate, truth)[~mask].mean()), 2)
        print(f"llanos {name}: {errors[name]} % in {seconds[name]} s", file=sys.stderr)
    chosen = runs["chosen"]
    return {
        "image": "Llanos 2019 real 7-band ColorChecker image, 342 x 408, Flea3 response",
        "spots": int(mask.sum()),
        "mean_relative_error_pct_off_spots": errors,
        "seconds": seconds,
        "appearance": chosen.appearance,
        "appearance_cross_validated_error_pct": {
            k: round(v, 2) for k, v in chosen.appearance_errors.items()
        },
        "prior": chosen.prior,
        "kriging_weight": chosen.kriging_weight,
        "cross_validated_error_pct": {k: round(v, 2) for k, v in chosen.held_out_errors.items()},
        "cost_ratio_chosen_over_fast": round(
            seconds["spectralize (cross-validated prior)"] / seconds["spectralize --fast"], 2
        ),
    }


def megapixel_case(side: int) -> dict:
    case = real_test_image("vhrel_clothes mosaic", side=side, seed=0)
    rgb = case.truth @ case.response
    spots, mask = _spots(case.truth, DEFAULT_GRID)
    response = case.response_per_nm()
    out: dict[str, Any] = {
        "image": f"{side} x {side} mosaic of VHREL clothes, 33 bands, {case.camera} + D65"
    }
    out["spots"] = int(mask.sum())
    default = CROSS_VALIDATION_PIXELS
    for name, fast, appearance, window, stride in (
        ("fast", True, "auto", default, None),
        ("fast every pixel", True, "auto", default, 1),
        ("cross-validated", False, "auto", default, None),
        ("cross-validated every pixel", False, "auto", default, 1),
        ("cross-validated window 250000 px", False, "auto", 250_000, None),
        ("cross-validated whole image", False, "auto", None, None),
        ("cross-validated rgbxy", False, "rgbxy", default, None),
    ):
        cpu_started = time.process_time()
        result, seconds = _timed(
            lambda fast=fast, appearance=appearance, window=window, stride=stride: _ours(
                rgb, spots, response, fast, appearance, window, stride
            )
        )
        out[f"{name}_s"] = seconds
        out[f"{name}_cpu_s"] = round(time.process_time() - cpu_started, 2)
        out[f"{name}_timings_s"] = {k: round(v, 2) for k, v in result.timings_s.items()}
        out[f"{name}_error_pct_off_spots"] = round(
            float(relative_error(result.cube, case.truth)[~mask].mean()), 2
        )
        out[f"{name}_appearance"] = result.appearance
        out[f"{name}_prior"] = result.prior
        out[f"{name}_kriging_weight"] = result.kriging_weight
        print(f"{side} px {name}: {seconds} s", file=sys.stderr)
    out["cost_ratio"] = round(out["cross-validated_s"] / out["fast_s"], 2)
    out["cpu_cost_ratio"] = round(out["cross-validated_cpu_s"] / out["fast_cpu_s"], 2)
    out["whole_image_cost_ratio"] = round(out["cross-validated whole image_s"] / out["fast_s"], 2)
    out["rgbxy_cost_ratio"] = round(out["cross-validated rgbxy_s"] / out["fast_s"], 2)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=1000)
    arguments = parser.parse_args()
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "date": time.strftime("%Y-%m-%d"),
                "llanos2019": llanos_case(),
                "megapixel": megapixel_case(arguments.side),
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
