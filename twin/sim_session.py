"""A small simulated gonioreflectometer session: dark frames, then two direction pairs through all
33 VariSpec bands, on a 32x32 window of the CoolSNAP K4 looking at the white standard under the
HMI lamp. Used by the resume and fault tests and as an example of driving ``hwbridge`` with the
twin. Run as ``python -m twin.sim_session STORE SEED [--resume] [--fault-rate F]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hwbridge.plans import dark_series, gonio_sample_run
from hwbridge.session import run_session
from hwbridge.store import CaptureStore
from twin.components import FINE_GRID, HMILamp, LiquidCrystalTunableFilter
from twin.sensor import Sensor
from twin.sim_devices import SimCamera, SimTunableFilter, VirtualRig
from twin.white_reference import white_reference_rates

__all__ = ["demo_plan", "run_demo_session"]

_PIXELS = 32


def demo_plan() -> list[dict]:
    """6 dark frames and 2 x 33 band frames (exposures in multiples of 1/15 s)."""
    lctf = LiquidCrystalTunableFilter.varispec("VS-10")
    exposures = np.full(len(lctf.band_centres_nm), 2 / 15)
    return dark_series("k4", [0.1, 1.0], frames_per_exposure=3) + gonio_sample_run(
        "k4", [0, 1], lctf.band_centres_nm, exposures
    )


def run_demo_session(
    store: Path,
    seed: int,
    *,
    resume: bool = False,
    fault_rate: float = 0.0,
    show_progress: bool = False,
) -> CaptureStore:
    sensor = Sensor("coolsnap_k4", roi=(_PIXELS, _PIXELS))
    lctf = LiquidCrystalTunableFilter.varispec("VS-10")
    rates = white_reference_rates(
        sensor, HMILamp(), lctf.transmission(FINE_GRID), distance_m=2.0
    ).sum(axis=0)
    by_band = dict(zip(lctf.band_centres_nm, rates, strict=True))
    rig = VirtualRig(fault_rate=fault_rate, fault_rng=np.random.default_rng([seed, 99]))

    def electron_rates(band_nm: float | None) -> np.ndarray:
        return np.full((_PIXELS, _PIXELS), by_band.get(band_nm, 0.0), np.float32)

    return run_session(
        store,
        demo_plan(),
        cameras={"k4": SimCamera(rig, sensor, electron_rates, name="k4")},
        tunable_filter=SimTunableFilter(rig),
        rig={"rig": "gonioreflectometer", "camera": "coolsnap_k4", "window_px": _PIXELS},
        backend="sim",
        seed=seed,
        resume=resume,
        show_progress=show_progress,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("store", type=Path)
    parser.add_argument("seed", type=int)
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--fault-rate", type=float, default=0.0)
    arguments = parser.parse_args()
    run_demo_session(
        arguments.store, arguments.seed, resume=arguments.resume, fault_rate=arguments.fault_rate
    )


if __name__ == "__main__":
    main()
