"""One design point of a gonioreflectometer sweep: virtual capture, processing, evaluation.

A point runs the twin's whole chain into its own folder, as a user would with the commands of
:mod:`twin.cli.gonio`:

1. the calibration session of its rig (``cal.capture.zarr``) and the calibration (Eq. 3.3, and
   the band exposure plan of Eq. 3.4; whole flicker periods for the HMI lamp only);
2. the measurement run of the material at the plan's direction sampling (``run.capture.zarr``);
3. processing into a BTF (``btf.zarr``, Eq. 3.6 and registration);
4. the measures (:data:`GONIO_MEASURES`): the run's capture time from the rig's timing model
   (:func:`twin.gonio.capture_time.estimate_plan_s`), the BTF's error at held-out directions
   against the truth at the band centres (:mod:`twin.validate.held_out`: Eq. 6.8 and
   Delta E94, so that the direction sampling and the filter's bandwidth count), the exposure
   totals and the storage.

Each store is resumed where a previous attempt stopped; ``result.json`` is written last and
atomically, so a point with one is finished and is never run again
(:mod:`twin.studies.sweep_points`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from recon.btf.processing import process_gonio
from recon.calibration.gonio import calibrate_gonio, lamp_rounding_s
from recon.errors import InputError
from twin.gonio.capture import (
    check_capture_settings,
    gonio_calibration_program,
    gonio_measurement_program,
    gonio_pairs,
)
from twin.gonio.render import GONIO_SPP
from twin.rigs.rig_config import GonioConfig
from twin.studies.sweep_plans import GonioPlan
from twin.studies.sweep_points import capture_into, storage_mb
from twin.validate.held_out import held_out_errors

if TYPE_CHECKING:
    from twin.studies.sweep_file import DesignPoint

__all__ = ["check_gonio_point", "measure_gonio_point"]

_CALIBRATION_PIXELS = 64


def check_gonio_point(point: DesignPoint) -> None:
    """Refuse a point whose plan its rig cannot take: pixels beyond the camera's, texels beyond
    the pixels, a sampling of which the robot reaches no pair."""
    config, plan = point.typed(GonioConfig, GonioPlan)
    check_capture_settings(config, pixels=plan.pixels, spp=plan.spp or GONIO_SPP)
    if plan.texels > plan.pixels:
        raise InputError(
            f"plan.texels: expected at most plan.pixels ({plan.pixels}), got {plan.texels}"
        )
    if not gonio_pairs(config, tuple(plan.rings)).poses:
        raise InputError(f"plan.rings: the robot reaches no pair of {plan.rings}")


def measure_gonio_point(point: DesignPoint, folder: Path) -> dict:
    """Capture, process and evaluate ``point`` in ``folder`` (module docstring); its measures
    (:func:`twin.studies.sweep_points.run_point` runs it and keeps the result)."""
    config, plan = point.typed(GonioConfig, GonioPlan)
    calibration_store = capture_into(
        gonio_calibration_program(pixels=_CALIBRATION_PIXELS, seed=point.seed, config=config),
        folder / "cal.capture.zarr",
    )
    calibration = calibrate_gonio(calibration_store, round_to_s=lamp_rounding_s(calibration_store))
    program = gonio_measurement_program(
        calibration.planned_exposure_s,
        material=point.material,
        rings=tuple(plan.rings),
        pixels=plan.pixels,
        spp=plan.spp or GONIO_SPP,
        seed=point.seed,
        config=config,
    )
    run_store = capture_into(program, folder / "run.capture.zarr")
    btf_path = folder / "btf.zarr"
    btf = process_gonio(
        run_store, calibration, btf_path, texels=plan.texels, resume=btf_path.exists()
    )
    errors = held_out_errors(btf_path).summary()
    pairs = len(program.poses)
    exposure_per_pair_s = float(calibration.planned_exposure_s.sum())
    return {
        "capture_time_h": program.dry_run()["estimated_duration_s"] / 3600,
        **errors,
        "exposure_per_pair_s": exposure_per_pair_s,
        "exposure_total_h": exposure_per_pair_s * pairs / 3600,
        "pairs": pairs,
        "pairs_registered": int(np.count_nonzero(btf.written())),
        "storage_mb": storage_mb(folder / "run.capture.zarr", btf_path),
    }
