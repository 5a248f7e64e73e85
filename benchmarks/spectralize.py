"""Spectralization at scale (1 megapixel x 33 bands, point spectra, k = 3).

Prints JSON: the time split (neighbour graph, linking its components, assembly of the Kronecker
parts, solve), wall and process CPU time with the machine's load, peak memory, energy and error, and
(with ``--lsqr-iterations N``) the thesis's LSQR for comparison, which at 1 MP takes long.

Run: ``python -m benchmarks.spectralize [--side 1000] [--lsqr-iterations 500]
[--prior regression]``.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import colour
import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from recon.experiments.sampling import known_spectra_from_mask, whisk_broom_mask
from recon.experiments.synthetic_images import material_mosaic
from recon.metrics import relative_error
from recon.spectra import DEFAULT_GRID
from recon.spectralize.solve import PointSpectra, reconstruct


def _scene(side: int, seed: int):
    wavelengths = DEFAULT_GRID.wavelengths_nm
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    names = ["dark skin", "blue sky", "orange", "purplish blue", "yellow green", "cyan"]
    spectra = np.array([[chart[name][w] for w in wavelengths] for name in names])
    image, _ = material_mosaic(spectra, (side, side), cells=200, seed=seed)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    response = np.array([cmfs[w] for w in wavelengths])
    response /= response.sum(axis=0)
    rgb = image @ response
    rgb += 0.01 * rgb.mean() * np.random.default_rng(seed).standard_normal(rgb.shape)
    return image, rgb, response


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--tol", type=float, nargs="+", default=[1e-6])
    parser.add_argument("--lsqr-iterations", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--spectral-noise",
        type=float,
        default=0.0,
        help="Gaussian noise on the known spectra, fraction of their mean (makes them full rank)",
    )
    parser.add_argument(
        "--prior",
        choices=("spectra", "regression"),
        default="spectra",
        help="What the appearance prior holds alike (recon.spectralize.solve.build_problem)",
    )
    args = parser.parse_args()
    truth, rgb, response = _scene(args.side, args.seed)
    pixels, spectra = known_spectra_from_mask(truth, whisk_broom_mask(truth.shape[:2]))
    noise = np.random.default_rng(args.seed + 1).standard_normal(spectra.shape)
    spectra = spectra + args.spectral_noise * spectra.mean() * noise
    known = PointSpectra(pixels, spectra)
    report = {"machine": machine_description(), "pixels": args.side**2, "bands": truth.shape[-1]}
    report["known_pixels"] = int(pixels.size)
    report["spectral_noise"] = args.spectral_noise
    report["prior"] = args.prior
    runs = [("multigrid", tol, 500) for tol in args.tol]
    if args.lsqr_iterations:
        runs.append(("lsqr", 1e-14, args.lsqr_iterations))
    for solver, tol, iterations in runs:
        started, cpu_started = time.perf_counter(), time.process_time()
        result = reconstruct(
            rgb,
            response,
            point_spectra=known,
            appearance="rgbxy",
            prior=args.prior,
            solver=solver,
            tol=tol,
            max_iterations=iterations,
        )
        report[f"{solver} tol={tol:g}" if solver == "multigrid" else solver] = {
            "total_s": round(time.perf_counter() - started, 2),
            "cpu_s": round(time.process_time() - cpu_started, 2),
            "load_average_1min": round(os.getloadavg()[0], 1),
            "timings_s": {k: round(v, 2) for k, v in result.timings_s.items()},
            "iterations": result.iterations,
            "energy": result.energy,
            "mean_relative_error_percent": float(relative_error(result.spectra, truth).mean()),
            "peak_rss_mib": peak_rss_mib(),
        }
        print(json.dumps(report, indent=1), flush=True)


if __name__ == "__main__":
    main()
