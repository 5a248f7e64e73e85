"""The cost of measuring the dome's spectra, and Eq. 10.2's exponent on dome stores. Prints JSON.

:mod:`twin.studies.dome_measured` on the dome study's stores (``twin.studies.dome_stores
.STORE_CAPTURE``: one stage position, 10 LEDs, the RGB cameras at 0, 37.5 and 75 degrees, 32
texels; captured into ``--out`` where missing): the measured LED spectrum and camera responses
against the twin's truths (also with a prior that has not seen the twin's camera), and per
material the dome BTF's mean Eq. 6.8 error from the stores calibrated with the measured spectra
against the twin's true ones, and at ``p_dyn`` 0, 0.5 and 0.6 (stores and the analytic path on
the same images).

Run: .venv/bin/python -m benchmarks.dome_measured [--out DIR] [--material M ...] [--seed N]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from benchmarks.common import machine_description, peak_rss_mib
from twin.studies.dome_measured import measured_study

MATERIALS = ("colorchecker16", "lego", "wallpaper", "red_fabric")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    parser.add_argument("--material", nargs="+", default=list(MATERIALS))
    parser.add_argument("--seed", type=int, default=0)
    arguments = parser.parse_args()
    folder = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-dome-measured-"))
    started = time.perf_counter()
    result = measured_study(
        folder,
        arguments.material,
        seed=arguments.seed,
        step=lambda name: print(f"[{time.perf_counter() - started:.0f} s] {name}", flush=True),
    )
    result |= {
        "machine": machine_description(),
        "wall_s": round(time.perf_counter() - started, 1),
        "peak_rss_mib": peak_rss_mib(),
    }
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
