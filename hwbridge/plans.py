"""Capture plans: the thesis's procedures as lists of steps, one frame per step.

A step is a plain dict (JSON-able, stored in the capture store's attributes) with the camera that
takes the frame, the frame kind, the exposure and whatever must be set before: filter band,
light, view (rig pose). Builders make the procedures of the thesis; ``estimate_duration_s`` gives
a dry run's duration.

References
----------
- The thesis, section 3.3 (50 dark frames per exposure time; 200 exposures for the response
  curve; white reference per run) and 4.1.1 (per direction pair: move, settle 1 s, per band: set
  the filter, expose, download; 130 ms switching and download per image).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from hwbridge.errors import BridgeInputError

__all__ = [
    "chart_photographs",
    "dark_series",
    "dome_run",
    "estimate_duration_s",
    "gonio_sample_run",
    "plan_start_times_s",
    "response_curve_series",
    "white_reference_run",
]


def _step(camera: str, kind: str, exposure_s: float, **settings: float | int) -> dict[str, object]:
    if not np.isfinite(exposure_s) or exposure_s <= 0:
        raise BridgeInputError(f"exposure_s: expected a positive exposure, got {exposure_s}")
    return {"camera": camera, "kind": kind, "exposure_s": float(exposure_s), **settings}


def dark_series(
    camera: str, exposures_s: Iterable[float], frames_per_exposure: int = 50
) -> list[dict]:
    """Dark frames: ``frames_per_exposure`` per exposure time, shutter closed (thesis 3.3)."""
    if frames_per_exposure < 1:
        raise BridgeInputError("frames_per_exposure: expected at least one frame")
    return [
        _step(camera, "dark", t, light_id=-1)
        for t in exposures_s
        for _ in range(frames_per_exposure)
    ]


def response_curve_series(
    camera: str, exposures_s: Iterable[float], *, light_id: int = 0
) -> list[dict]:
    """One frame of a static scene per exposure time, for the response curve (Robertson)."""
    return [_step(camera, "oecf", t, light_id=light_id) for t in exposures_s]


def gonio_sample_run(
    camera: str,
    view_ids: Iterable[int],
    band_centres_nm: Iterable[float],
    band_exposures_s: Iterable[float],
) -> list[dict]:
    """Per direction pair (``view_id``), per band: tune the filter, expose (thesis 4.1.1)."""
    bands = list(band_centres_nm)
    exposures = list(band_exposures_s)
    if len(bands) != len(exposures):
        raise BridgeInputError(
            f"band_exposures_s: expected {len(bands)} exposures, got {len(exposures)}"
        )
    return [
        _step(camera, "sample", t, view_id=int(view), band_nm=float(band), light_id=0)
        for view in view_ids
        for band, t in zip(bands, exposures, strict=True)
    ]


def white_reference_run(
    camera: str, band_centres_nm: Iterable[float], band_exposures_s: Iterable[float]
) -> list[dict]:
    """The white standard through every band before a run, for the factors F'_lambda (3.3)."""
    return [
        _step(camera, "white", t, band_nm=float(band), light_id=0)
        for band, t in zip(band_centres_nm, band_exposures_s, strict=True)
    ]


def chart_photographs(
    camera: str, exposures_s: Iterable[float], light_ids: Iterable[int]
) -> list[dict]:
    """Colour-chart photographs, one per light and exposure (thesis 9.3)."""
    return [
        _step(camera, "chart", t, light_id=int(light)) for light in light_ids for t in exposures_s
    ]


def dome_run(
    rgb_cameras: list[str],
    spectral_camera: str,
    *,
    stage_positions: int,
    leds: int,
    rgb_exposure_s: float,
    spectral_exposure_s: float,
    spectral_bands_nm: list[float],
) -> list[dict]:
    """The dome procedure (thesis 10.2.2): per stage position an alignment frame with all LEDs on
    for every camera, then per LED one frame of every RGB camera and one of the spectral camera
    in the band its schedule gives that (position, LED) (cycled through ``spectral_bands_nm``).
    The view of a step is its stage position."""
    if stage_positions < 1 or leds < 1 or not spectral_bands_nm:
        raise BridgeInputError("dome_run: expected stage positions, LEDs and at least one band")
    plan, schedule = [], 0
    for position in range(stage_positions):
        for camera in [*rgb_cameras, spectral_camera]:
            exposure = spectral_exposure_s if camera == spectral_camera else rgb_exposure_s
            plan.append(_step(camera, "alignment", exposure, view_id=position, light_id=-2))
        for led in range(leds):
            for camera in rgb_cameras:
                plan.append(_step(camera, "sample", rgb_exposure_s, view_id=position, light_id=led))
            band = spectral_bands_nm[schedule % len(spectral_bands_nm)]
            plan.append(
                _step(
                    spectral_camera,
                    "sample",
                    spectral_exposure_s,
                    view_id=position,
                    light_id=led,
                    band_nm=float(band),
                )
            )
            schedule += 1
    return plan


def plan_start_times_s(
    plan: list[dict], *, per_frame_overhead_s: float = 0.13, per_view_move_s: float = 6.0
) -> np.ndarray:
    """When each step's exposure starts, in seconds from the session start: moves to a new view,
    then exposure plus switching/download per frame (thesis 4.1.1). Fixed by the plan alone, so a
    resumed session sees the same lamp phase at every step as an uninterrupted one."""
    starts, clock, view = [], 0.0, None
    for step in plan:
        step_view = step.get("view_id", -1)
        if step_view != -1 and step_view != view:
            clock += per_view_move_s
            view = step_view
        starts.append(clock)
        clock += float(step["exposure_s"]) + per_frame_overhead_s
    return np.array(starts)


def estimate_duration_s(
    plan: list[dict], *, per_frame_overhead_s: float = 0.13, per_view_move_s: float = 6.0
) -> float:
    """Dry-run duration: exposures, per-frame switching/download, and a move per new view."""
    starts = plan_start_times_s(
        plan, per_frame_overhead_s=per_frame_overhead_s, per_view_move_s=per_view_move_s
    )
    return float(starts[-1] + float(plan[-1]["exposure_s"]) + per_frame_overhead_s)
