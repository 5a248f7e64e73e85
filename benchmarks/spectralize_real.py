"""Spectralization against its peers on real spectra (chapter 7 whisk-broom protocol). Prints JSON.

Cases: :mod:`recon.experiments.real_images` (Llanos's real seven-band image, and a mosaic and a
smooth blend of each real reflectance set under a real camera and D65). Protocol: 250 known
spectra on a regular grid, spots of 0.5 % of the image width, Gaussian RGB noise of 1 % of the
mean (``recon.experiments.sparse.run_protocol``); every method of
``recon.experiments.sparse.METHODS``. Per image and seed: the mean relative error (Eq. 6.8, %) of
every method, the best peer, each spectralization variant's ratio to it (the default of
``spectwin spectralize``: the chosen appearance space and prior blended with Murakami's kriged
estimate, counted against the target), the prior that ``choose_prior`` picks with its
cross-validated errors, and the seconds per method. With ``--spot-fractions``, the whisk-broom
spot size is also swept on the images where a peer wins.

Also Eq. 10.2 with noisy band images (``recon.experiments.real_images.holder_bar_case``: a 96 px
clothes mosaic with a black bar across it, nine 5 %-noisy band images filtered at 2 px, 1 % RGB
noise): the mean error of the lit pixels beside
the bar for ``p_dyn`` 0 and 1 and the floor of the scale (``DYNAMIC_FLOOR``) at 0.1 % and 5 %.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.spectralize_real [--seeds 0 1] [--side 192]
    [--cases llanos2019 ...]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from benchmarks.common import machine_description
from recon.experiments.real_images import (
    holder_bar_case,
    real_test_image,
    real_test_image_names,
)
from recon.experiments.sampling import add_rgb_noise, known_spectra_from_mask, whisk_broom_mask
from recon.experiments.sparse import METHODS, run_protocol
from recon.metrics import relative_error
from recon.spectralize import choose_prior, solve
from recon.spectralize.solve import EnergyWeights, reconstruct

VARIANTS = tuple(name for name in METHODS if name.startswith("spectralization"))
PEERS = tuple(name for name in METHODS if name not in VARIANTS)
CHOSEN = "spectralization chosen prior"
DEFAULT = "spectralization chosen appearance, prior and kriging"
"""What ``spectwin spectralize`` does by default; the target (at most 0.7 of the best peer on
mosaics and real images, at most 1.0 on smooth blends) is counted for it."""


def _timed_errors(truth, response, mask, seed) -> tuple[dict, dict, dict]:
    """Every method's mean error and seconds, and ``choose_prior``'s cross-validated errors.
    The chosen prior's reconstruction is the run of that prior (the same solve), its time that
    run's plus the choice's."""
    errors, seconds = {}, {}
    for name in METHODS:
        if name == CHOSEN:
            continue
        started = time.perf_counter()
        result = run_protocol(truth, response, mask, methods=(name,), seed=seed)
        seconds[name] = round(time.perf_counter() - started, 2)
        errors[name] = round(result.mean_errors[name], 3)
    pixels, spectra = known_spectra_from_mask(truth, mask)
    rgb = add_rgb_noise(truth @ response, 0.01, np.random.default_rng(seed))
    started = time.perf_counter()
    choice = choose_prior(
        rgb,
        response,
        pixels,
        spectra,
        appearance="rgbxy",
        weights=EnergyWeights(delta=0.0),
        tol=1e-8,
    )
    run = "spectralization" if choice.prior == "spectra" else "spectralization regression prior"
    errors[CHOSEN] = errors[run]
    seconds[CHOSEN] = round(time.perf_counter() - started + seconds[run], 2)
    return errors, seconds, {k: round(v, 3) for k, v in choice.held_out_errors.items()}


def _band_image_floor_case() -> dict:
    case = holder_bar_case()
    chosen_floor, out = solve.DYNAMIC_FLOOR, {}
    for floor in (1e-3, chosen_floor):
        solve.DYNAMIC_FLOOR = floor
        for p_dyn in (0.0, 1.0):
            spectra = reconstruct(
                case.rgb,
                case.response,
                band_images=case.band_images,
                p_dyn=p_dyn,
                appearance="rgbxy",
            ).spectra
            errors = relative_error(spectra, case.truth)
            out[f"floor {floor} p_dyn {p_dyn}"] = {
                "lit_beside_bar_pct": round(float(errors[case.beside].mean()), 2),
                "lit_pct": round(float(errors[~case.bar].mean()), 2),
            }
    solve.DYNAMIC_FLOOR = chosen_floor
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--side", type=int, default=192)
    parser.add_argument("--cases", nargs="*", default=None, help="default: every real image")
    parser.add_argument("--spot-fractions", type=float, nargs="*", default=[0.01, 0.02, 0.04])
    arguments = parser.parse_args()
    started = time.perf_counter()
    images = {}
    for name in arguments.cases or real_test_image_names():
        for seed in arguments.seeds:
            case = real_test_image(name, side=arguments.side, seed=seed)
            mask = whisk_broom_mask(case.truth.shape[:2])
            errors, seconds, held_out = _timed_errors(case.truth, case.response, mask, seed)
            best = min(PEERS, key=errors.__getitem__)
            entry = {
                "camera": case.camera,
                "shape": list(case.truth.shape),
                "mean_relative_error_pct": errors,
                "best_peer": best,
                "ratio_to_best_peer": {v: round(errors[v] / errors[best], 3) for v in VARIANTS},
                "cross_validated_error_pct": held_out,
                "seconds": seconds,
            }
            if errors[DEFAULT] > 0.7 * errors[best]:
                entry["spot_fraction_sweep"] = {
                    str(fraction): {
                        key: round(value, 3)
                        for key, value in run_protocol(
                            case.truth,
                            case.response,
                            whisk_broom_mask(case.truth.shape[:2], spot_fraction=fraction),
                            methods=(DEFAULT, best),
                            seed=seed,
                        ).mean_errors.items()
                    }
                    for fraction in arguments.spot_fractions
                }
            images[f"{name} seed {seed}"] = entry
            print(f"{name} seed {seed}: {errors}", flush=True, file=sys.stderr)
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "seeds": arguments.seeds,
                "side": arguments.side,
                "protocol": "whisk-broom, 250 spots of 0.5 % of the width, 1 % RGB noise",
                "images": images,
                "images_within_target": int(
                    sum(
                        e["ratio_to_best_peer"][DEFAULT] <= (1.0 if "blend" in name else 0.7)
                        for name, e in images.items()
                    )
                ),
                "band_image_floor": _band_image_floor_case(),
                "seconds": round(time.perf_counter() - started, 1),
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
