"""What the simulated rigs' capture programs share (``twin.gonio.capture``,
``twin.dome.programs``): the checks of their settings before anything is made, and capturing
their plan in this process or over a Dask cluster (:func:`twin.devices.cluster.run_capture`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from hwbridge.lab import Lab
from hwbridge.schema import RigAttrs
from hwbridge.store import CaptureStore
from recon.errors import InputError
from twin.devices.cluster import run_capture
from twin.devices.lab_devices import LabDevices
from twin.devices.sim_devices import SimDomeDevices, SimGonioDevices
from twin.sensor.model import Sensor

if TYPE_CHECKING:
    from distributed import Client
    from typing_extensions import TypeIs

__all__ = ["ProgramCapture", "check_exposures", "check_fault_rate", "check_seed", "is_whole"]


def is_whole(value: object) -> TypeIs[int | np.integer]:
    """Whether ``value`` is a whole number (not a bool)."""
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


def check_seed(seed: object) -> None:
    """Refuse a seed that is not a whole number >= 0."""
    if not is_whole(seed) or seed < 0:
        raise InputError(f"seed: expected a whole number >= 0, got {seed}")


def check_fault_rate(fault_rate: object) -> None:
    """Refuse an injected fault rate that is not a probability (NaN included)."""
    if not isinstance(fault_rate, int | float | np.floating) or not 0.0 <= fault_rate <= 1.0:
        raise InputError(f"fault_rate: expected a probability in [0, 1], got {fault_rate}")


def check_exposures(plan: list[dict], sensors: Mapping[str, Sensor]) -> None:
    """Refuse a plan with an exposure outside the range of the camera that takes it."""
    for camera, sensor in sensors.items():
        low, high = sensor.config.exposure_range_s
        times = {step["exposure_s"] for step in plan if step["camera"] == camera}
        outside = sorted(time for time in times if not low <= time <= high)
        if outside:
            shown = ", ".join(f"{value:g}" for value in outside[:5])
            raise InputError(
                f"exposures: the plan has exposures ({shown} s) outside the "
                f"{sensor.config.name}'s range {low:g}..{high:g} s"
            )


class ProgramCapture:
    """Capturing of a program that holds its ``plan``, its ``devices`` (a recipe that builds
    them, and pickles for the workers of a cluster), the store's ``rig`` attribute (the model of
    the rig's kind) and the session ``seed``."""

    plan: list[dict[str, Any]]
    devices: SimDomeDevices | SimGonioDevices
    rig: RigAttrs
    seed: int

    def run(
        self,
        store: str | Path,
        *,
        resume: bool = False,
        show_progress: bool = False,
        client: Client | None = None,
        lab: Lab | None = None,
    ) -> CaptureStore:
        """Capture the plan into ``store`` (or continue it), in this process or over
        ``client``'s cluster (:func:`twin.devices.cluster.run_capture`): the frames are the
        same. With ``lab``, a devices file, its real devices fill the roles it names
        (:class:`twin.devices.lab_devices.LabDevices`; in this process only)."""
        if lab is not None and client is not None:
            raise InputError(
                "a capture with a lab's devices runs in this process, not on a cluster"
            )
        return run_capture(
            Path(store),
            self.plan,
            self.devices if lab is None else LabDevices(lab, self.devices),
            rig=self.rig,
            seed=self.seed,
            resume=resume,
            show_progress=show_progress,
            client=client,
        )
