"""A small simulated gonioreflectometer session: dark frames, then two direction pairs through all
33 VariSpec bands, on a 32x32 window of the CoolSNAP K4. By default the camera sees the white
standard under the HMI lamp (analytic); with ``rendered=True`` it sees the colour checker on its
holder, rendered by Mitsuba for each direction pair. Used by the resume and fault tests and as an
example of driving ``hwbridge`` with the twin.
Built as a :class:`twin.gonio.capture.CaptureProgram` (:func:`demo_program`, the ``demo``
program of ``spectwin capture``). Run as ``python -m twin.gonio.sim_session STORE SEED [--resume]
[--fault-rate F]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from hwbridge.errors import SessionInterrupted, StoreBusy
from hwbridge.plans import dark_series, gonio_sample_run, plan_start_times_s
from hwbridge.schema import GonioRigAttrs
from hwbridge.store import CaptureStore
from twin.components.lamps import HMILamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.devices.sim_devices import Signal, SimGonioDevices
from twin.gonio.capture import CaptureProgram, GonioPairs
from twin.gonio.signals import RenderedGonioSignal, WhiteReferenceSignal
from twin.materials import load_material
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["demo_plan", "demo_program", "run_demo_session"]

_PIXELS = 32


def demo_plan() -> list[dict]:
    """6 dark frames and 2 x 33 band frames (exposures in multiples of 1/15 s)."""
    lctf = LiquidCrystalTunableFilter.varispec("VS-10")
    exposures = np.full(len(lctf.band_centres_nm), 2 / 15)
    return dark_series("k4", [0.1, 1.0], frames_per_exposure=3) + gonio_sample_run(
        "k4", [0, 1], lctf.band_centres_nm, exposures
    )


_VIEWS = ((30.0, 0.0, 15.0, 180.0), (45.0, 90.0, 30.0, 250.0))  # light, view: (theta, phi)


def demo_program(
    seed: int = 0, *, fault_rate: float = 0.0, rendered: bool = False
) -> CaptureProgram:
    """The session of the module docstring, checked and not yet captured; ``fault_rate``
    (a probability in [0, 1]) injects device faults drawn from ``seed``."""
    sensor = Sensor("coolsnap_k4", roi=(_PIXELS, _PIXELS))
    plan = demo_plan()
    config = load_rig("gonio")
    light = direction(np.array([v[0] for v in _VIEWS]), np.array([v[1] for v in _VIEWS]))
    view = direction(np.array([v[2] for v in _VIEWS]), np.array([v[3] for v in _VIEWS]))
    poses = GonioPairs(config, light, view).poses  # both pairs are reachable
    signal: Signal
    if rendered:
        signal = RenderedGonioSignal(config, load_material("colorchecker16"), poses, pixels=_PIXELS)
    else:
        signal = WhiteReferenceSignal(sensor, HMILamp())
    devices = SimGonioDevices(
        "k4",
        sensor,
        signal,
        plan_start_times_s(plan),
        len(_VIEWS),
        fault_rate=float(fault_rate),
        fault_seed=seed,
    )
    rig = GonioRigAttrs(
        rig="gonioreflectometer",
        program="demo",
        camera="coolsnap_k4",
        camera_id="k4",
        window_px=_PIXELS,
        lamp="hmi",
    )
    return CaptureProgram("demo", plan, devices, rig, seed, dict(enumerate(poses)))


def run_demo_session(
    store: Path,
    seed: int,
    *,
    resume: bool = False,
    fault_rate: float = 0.0,
    rendered: bool = False,
    show_progress: bool = False,
    client: Client | None = None,
) -> CaptureStore:
    """Run (or resume) the session into ``store``; see the module docstring. With a Dask
    ``client`` it runs over its cluster (:mod:`twin.devices.cluster`): the frames are the same, the
    injected faults (drawn afresh in every task) fall on other steps."""
    program = demo_program(seed, fault_rate=fault_rate, rendered=rendered)
    return program.run(store, resume=resume, show_progress=show_progress, client=client)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("store", type=Path)
    parser.add_argument("seed", type=int)
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--fault-rate", type=float, default=0.0)
    arguments = parser.parse_args()
    try:
        run_demo_session(
            arguments.store,
            arguments.seed,
            resume=arguments.resume,
            fault_rate=arguments.fault_rate,
        )
    except SessionInterrupted as stop:
        print(f"interrupted after {stop.done} of {stop.total} frames", file=sys.stderr)
        raise SystemExit(130) from None
    except StoreBusy as busy:
        print(f"error: {busy}", file=sys.stderr)
        raise SystemExit(1) from None


if __name__ == "__main__":
    main()
