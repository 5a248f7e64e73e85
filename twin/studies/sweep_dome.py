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
from typing import TYPE_CHECKING, Annotated

from pydantic import Field

from hwbridge.dome_layout import SPECTRAL_CAMERA
from recon.calibration.dome_capture import calibrate_dome
from recon.dome.processing import TARGET_RELATIVE_NOISE, process_dome
from recon.errors import SpectwinInputError
from twin.dome.programs import (
    DEFAULT_SPP,
    DomeCaptureSize,
    dome_calibration_program,
    dome_plan_parts,
    dome_run_program,
)
from twin.dome.setup import THESIS_LONGEST_BAND_S
from twin.rigs.rig_config import DomeConfig
from twin.rigs.yaml_config import StrictModel
from twin.studies.sweep_points import SHARED_MEASURES, capture_into, storage_mb
from twin.validate.dome_evaluation import evaluate_dome

if TYPE_CHECKING:
    from twin.studies.sweep_file import DesignPoint

__all__ = ["DOME_MEASURES", "DomePlan", "measure_dome_point"]

DOME_MEASURES = {
    "error_pct": "BTF vs truth, mean Eq. 6.8 (%)",
    "delta_e94": "BTF vs truth, mean Delta E94",
    "per_texel_error_pct": "BTF vs truth, per-texel Eq. 6.8 (%)",
    "spectral_exposure_h": "exposure of the spectral camera's frames in the run (h)",
    "rgb_exposure_h": "exposure of each RGB camera's frames in the run (h)",
    "pairs": "direction pairs in the BTF",
    **SHARED_MEASURES,
}
"""The measures of a dome design point, with their units."""


class DomePlan(StrictModel):
    """The capture and processing settings of a dome point (the ``plan.`` parameters).

    Attributes
    ----------
    stage_positions, leds, rgb_cameras, texels, spp
        The capture's size (:class:`twin.dome.programs.DomeCaptureSize`).
    dark_frames
        Dark frames per spectral exposure time in the calibration (thesis 10.3: 200).
    longest_band_s
        Exposure of the spectral camera's weakest band (s); sets :math:`t_{base}` (10.4).
    schedule_images
        RGB images the 30 bands are packed into, each band once; ``None``: the thesis's 10
        images with the noisiest bands twice.
    target_relative_noise
        What the band images' filters leave (the filter size, Figure 10.5).
    """

    stage_positions: Annotated[int, Field(ge=1, le=24)] = 1
    leds: Annotated[int, Field(ge=1, le=198)] = 10
    rgb_cameras: Annotated[int, Field(ge=1, le=11)] = 3
    texels: Annotated[int, Field(ge=8, le=512)] = 32
    spp: Annotated[int, Field(ge=1, le=65536)] = DEFAULT_SPP
    dark_frames: Annotated[int, Field(ge=1, le=10000)] = 16
    longest_band_s: Annotated[float, Field(gt=0, le=600)] = THESIS_LONGEST_BAND_S
    schedule_images: Annotated[int, Field(ge=1, le=198)] | None = None
    target_relative_noise: Annotated[float, Field(gt=0, lt=1)] = TARGET_RELATIVE_NOISE

    @property
    def size(self) -> DomeCaptureSize:
        return DomeCaptureSize(
            stage_positions=self.stage_positions,
            leds=self.leds,
            rgb_cameras=self.rgb_cameras,
            texels=self.texels,
            spp=self.spp,
        )

    def check(self, config: DomeConfig) -> None:
        """Refuse a size the rig cannot take, a band schedule of more images than LEDs (the
        LEDs take the schedule's images in turn: the bands of the images past the last LED would
        never be exposed), and exposures its camera cannot make."""
        if self.schedule_images is not None and self.schedule_images > self.leds:
            raise SpectwinInputError(
                f"schedule_images: expected at most plan.leds ({self.leds}) images, got "
                f"{self.schedule_images}: the bands of the images past the last LED would never "
                "be exposed"
            )
        dome_plan_parts(
            config,
            self.size,
            longest_band_s=self.longest_band_s,
            schedule_images=self.schedule_images,
        )


def _exposure_h(plan: list[dict], spectral: bool) -> float:
    """Summed exposure of the spectral camera's frames, or of one RGB camera's, in hours."""
    cameras = [step["camera"] for step in plan if step["camera"] != SPECTRAL_CAMERA]
    camera = SPECTRAL_CAMERA if spectral else cameras[0]
    return sum(step["exposure_s"] for step in plan if step["camera"] == camera) / 3600


def measure_dome_point(point: DesignPoint, folder: Path) -> dict:
    """Capture, process and evaluate ``point`` in ``folder`` (module docstring); its measures
    (:func:`twin.studies.sweep_points.run_point` runs it and keeps the result)."""
    config, plan = point.rig, point.plan
    calibration_program = dome_calibration_program(
        size=plan.size,
        dark_frames=plan.dark_frames,
        seed=point.seed,
        config=config,
        longest_band_s=plan.longest_band_s,
        schedule_images=plan.schedule_images,
    )
    calibration = calibrate_dome(capture_into(calibration_program, folder / "cal.capture.zarr"))
    program = dome_run_program(
        point.material,
        size=plan.size,
        seed=point.seed,
        config=config,
        longest_band_s=plan.longest_band_s,
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
