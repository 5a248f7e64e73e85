"""``spectwin spectralize``'s defaults for large images against the plain path: does it choose
the same appearance space, prior and kriging weight, and reconstruct as well? Prints JSON, one
line per case.

Two comparisons (``--against``):

- ``whole``: cross-validation in a central window of the image
  (``recon.image_spectralization.window``) against the whole image. At ``--side`` 600 a window
  of about 250 000 px would be most of the image, so the window is asked at ``--share`` of the
  pixels (default a quarter).
- ``every-pixel``: the hierarchical solve of the RGBXY space in the folds and the final solve
  (``recon.spectralize.hierarchy``, every second pixel of every second row) against every
  pixel solved (``sample_stride=1``), both with the default window.

The cases: the twelve mosaics and smooth blends of real reflectance sets of
``recon.experiments.real_images`` at ``--side`` pixels (default 600), spots at 1 % of the pixels
or ``--spots`` of them (single pixels on a regular grid) and 1 % Gaussian RGB noise, the
camera-times-D65 response per nanometre. Per case and setting: the space, prior and kriging
weight chosen, the mean relative error (Eq. 6.8, %) off the spots against the truth, and the
seconds of the cross-validation and in all.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.spectralize_window [--side 600] [--seeds 0]
    [--against whole|every-pixel]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from benchmarks.common import machine_description
from recon.experiments.real_images import real_test_image, real_test_image_names
from recon.experiments.sampling import add_rgb_noise, whisk_broom_mask
from recon.image_spectralization.run import spectralize_image
from recon.image_spectralization.spots import SpotSpectra
from recon.metrics import relative_error
from recon.spectra import DEFAULT_GRID, SampledSpectra


def _settings(against: str, side: int, share: float) -> tuple[tuple[str, dict], ...]:
    """The two settings of ``spectralize_image`` compared (module description)."""
    if against == "whole":
        return (
            ("window", {"cross_validation_pixels": int(share * side * side)}),
            ("whole", {"cross_validation_pixels": None}),
        )
    return (("hierarchical", {}), ("every_pixel", {"sample_stride": 1}))


def case_run(
    name: str, side: int, share: float, seed: int, spots_count: int | None, against: str
) -> dict:
    """One case in both settings (module description)."""
    case = real_test_image(name, side=side, seed=seed)
    count = spots_count or int(round(0.01 * side * side))
    mask = whisk_broom_mask((side, side), n_spots=count, spot_fraction=1e-3)
    rows, cols = np.nonzero(mask)
    spots = SpotSpectra(
        np.stack([cols, rows], 1), SampledSpectra(DEFAULT_GRID, case.truth[rows, cols]), "bench"
    )
    response = case.response_per_nm()
    rgb = add_rgb_noise(case.truth @ case.response, 0.01, np.random.default_rng(seed))
    out: dict = {"case": name, "seed": seed, "camera": case.camera, "spots": int(mask.sum())}
    settings = _settings(against, side, share)
    for label, setting in settings:
        started = time.perf_counter()
        result = spectralize_image(rgb, spots, response, **setting)
        seconds = time.perf_counter() - started
        out[label] = {
            "appearance": result.appearance,
            "prior": result.prior,
            "kriging_weight": round(result.kriging_weight, 2),
            "error_pct_off_spots": round(
                float(relative_error(result.cube, case.truth)[~mask].mean()), 3
            ),
            "held_out_spots": int(np.isfinite(result.spot_errors).sum()),
            "cross_validation_s": round(result.timings_s["cross_validation"], 1),
            "total_s": round(seconds, 1),
        }
    (first, _), (second, _) = settings
    out["same_choice"] = all(out[first][key] == out[second][key] for key in ("appearance", "prior"))
    out[f"error_ratio_{first}_over_{second}"] = round(
        out[first]["error_pct_off_spots"] / out[second]["error_pct_off_spots"], 3
    )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=600)
    parser.add_argument("--share", type=float, default=0.25)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--cases", nargs="*", default=None)
    parser.add_argument("--spots", type=int, default=None, help="default: 1 %% of the pixels")
    parser.add_argument("--against", choices=("whole", "every-pixel"), default="whole")
    args = parser.parse_args()
    names = args.cases or [n for n in real_test_image_names() if n != "llanos2019"]
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "side": args.side,
                "share": args.share,
                "against": args.against,
            }
        )
    )
    for seed in args.seeds:
        for name in names:
            print(
                json.dumps(case_run(name, args.side, args.share, seed, args.spots, args.against)),
                flush=True,
            )
            print(f"{name} seed {seed} done", file=sys.stderr)


if __name__ == "__main__":
    main()
