"""One design point of a dome sweep: virtual calibration, capture, processing and evaluation.

A point runs the dome's chain into its own folder, as ``spectwin capture``, ``calibrate``,
``process`` and ``evaluate`` would (thesis 10.2-10.4):

1. the calibration session at the point's size (``cal.capture.zarr``; its dark frames span the
   run's band exposures) and :func:`recon.calibration.dome_capture.calibrate_dome`;
2. the measurement run of the material (``run.capture.zarr``): per stage position and LED the
   RGB cameras' HDR sets and the spectral camera's scheduled bands, the weakest band exposed
   ``longest_band_s`` (:math:`t_\\lambda = t_{base}/\\sqrt{E L}`, which sets :math:`t_{base}`)
   and the 30 bands packed into ``schedule_images`` RGB images;
3. processing into a spectral BTF (``btf.zarr``, Eq. 10.12), the band images filtered down to
   ``target_relative_noise`` (Figure 10.5's filter sizes, Eq. 10.1);
4. the measures (:data:`DOME_MEASURES`): the run's capture time from the rig's timing model, the
   BTF's error against the truth (Eq. 6.8 and Delta E94,
   :func:`twin.validate.dome_evaluation.evaluate_dome`), the exposure totals and the storage.

Stores are continued where a previous attempt stopped; ``result.json`` comes last
(:mod:`twin.studies.sweep_points`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from hwbridge.dome_layout import SPECTRAL_CAMERA
from recon.calibration.dome_capture import calibrate_dome
from recon.dome.processing import process_dome
from recon.errors import InputError
from twin.dome.programs import (
    DEFAULT_SPP,
    DomeCaptureSize,
    dome_calibration_program,
    dome_plan_parts,
    dome_run_program,
)
from twin.dome.setup import THESIS_LONGEST_BAND_S
from twin.rigs.rig_config import DomeConfig
from twin.studies.sweep_plans import DomePlan
from twin.studies.sweep_points import capture_into, storage_mb
from twin.validate.dome_evaluation import evaluate_dome

if TYPE_CHECKING:
    from twin.studies.sweep_file import DesignPoint
    from twin.studies.sweep_plans import DomePlan

__all__ = ["check_dome_point", "measure_dome_point"]


def _size(plan: DomePlan) -> DomeCaptureSize:
    return DomeCaptureSize(
        stage_positions=plan.stage_positions,
        leds=plan.leds,
        rgb_cameras=plan.rgb_cameras,
        texels=plan.texels,
        spp=plan.spp or DEFAULT_SPP,
    )


def check_dome_point(point: DesignPoint) -> None:
    """Refuse a point whose plan its rig cannot take: a size beyond the rig's, a band schedule
    of more images than LEDs (the LEDs take the schedule's images in turn: the bands of the
    images past the last LED would never be exposed), exposures no schedule fits."""
    config, plan = point.typed(DomeConfig, DomePlan)
    if plan.schedule_images is not None and plan.schedule_images > plan.leds:
        raise InputError(
            f"schedule_images: expected at most plan.leds ({plan.leds}) images, got "
            f"{plan.schedule_images}: the bands of the images past the last LED would never "
            "be exposed"
        )
    dome_plan_parts(
        config,
        _size(plan),
        longest_band_s=plan.longest_band_s or THESIS_LONGEST_BAND_S,
        schedule_images=plan.schedule_images,
    )


def _exposure_h(plan: list[dict], spectral: bool) -> float:
    """Summed exposure of the spectral camera's band frames, or of one RGB camera's HDR sets
    (the ``sample`` frames; not the alignment frames), in hours."""
    cameras = [step["camera"] for step in plan if step["camera"] != SPECTRAL_CAMERA]
    camera = SPECTRAL_CAMERA if spectral else cameras[0]
    frames = [step for step in plan if step["camera"] == camera and step["kind"] == "sample"]
    return sum(step["exposure_s"] for step in frames) / 3600


def measure_dome_point(point: DesignPoint, folder: Path) -> dict:
    """Capture, process and evaluate ``point`` in ``folder`` (module docstring); its measures
    (:func:`twin.studies.sweep_points.run_point` runs it and keeps the result)."""
    config, plan = point.typed(DomeConfig, DomePlan)
    calibration_program = dome_calibration_program(
        size=_size(plan),
        dark_frames=plan.dark_frames,
        seed=point.seed,
        config=config,
        longest_band_s=plan.longest_band_s or THESIS_LONGEST_BAND_S,
        schedule_images=plan.schedule_images,
    )
    calibration = calibrate_dome(capture_into(calibration_program, folder / "cal.capture.zarr"))
    program = dome_run_program(
        point.material,
        size=_size(plan),
        seed=point.seed,
        config=config,
        longest_band_s=plan.longest_band_s or THESIS_LONGEST_BAND_S,
        schedule_images=plan.schedule_images,
    )
    run_store = capture_into(program, folder / "run.capture.zarr")
    btf_path = folder / "btf.zarr"
    btf = process_dome(
        run_store,
        calibration,
        btf_path,
        resume=btf_path.exists(),
        target_relative_noise=plan.target_relative_noise,
    )
    summary = evaluate_dome(btf_path).summary()
    what = "diffuse_fields" if "mean_delta_e94_diffuse_fields" in summary else "material_texels"
    return {
        "capture_time_h": program.dry_run()["estimated_duration_s"] / 3600,
        "error_pct": summary[f"mean_relative_error_{what}_pct"],
        "delta_e94": summary[f"mean_delta_e94_{what}"],
        "per_texel_error_pct": summary["per_texel_relative_error_pct"],
        "spectral_exposure_h": _exposure_h(program.plan, spectral=True),
        "rgb_exposure_h": _exposure_h(program.plan, spectral=False),
        "pairs": int(btf.n_pairs),
        "storage_mb": storage_mb(folder / "run.capture.zarr", btf_path),
    }
