"""Capture plans: the thesis's procedures as lists of steps, one frame per step.

A step is a plain dict (JSON-able, stored in the capture store's attributes and read back as a
:class:`hwbridge.schema.PlanStep`) with the camera that takes the frame, the frame kind, the
exposure and whatever must be set before: filter band, light, view (rig pose). Builders make
the procedures of the thesis; ``estimate_duration_s`` gives a dry run's duration. The dome's
procedures are in :mod:`hwbridge.dome_plans`.

References
----------
- The thesis, section 3.3 (50 dark frames per exposure time; 200 exposures for the response
  curve; white reference per run) and 4.1.1 (per direction pair: move, settle 1 s, per band: set
  the filter, expose, download; 130 ms switching and download per image).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from hwbridge.errors import InputError
from hwbridge.schema import NO_LIGHT, NO_VIEW

__all__ = [
    "chart_photographs",
    "dark_series",
    "estimate_duration_s",
    "gonio_sample_run",
    "plan_step",
    "plan_start_times_s",
    "response_curve_series",
    "white_reference_run",
]


def plan_step(
    camera: str,
    kind: str,
    exposure_s: float,
    *,
    light_id: int | None = None,
    view_id: int | None = None,
    band_nm: float | None = None,
    tilt_deg: float | None = None,
) -> dict[str, Any]:
    """One step (a :class:`~hwbridge.schema.PlanStep` as the store records it): ``camera``
    takes a frame of ``kind`` at ``exposure_s`` after the settings given (light, view, band,
    wedge tilt) are set; a non-positive or non-finite exposure is refused.

    Examples
    --------
    >>> plan_step("k4", "dark", 0.5, light_id=NO_LIGHT)
    {'camera': 'k4', 'kind': 'dark', 'exposure_s': 0.5, 'light_id': -1}
    """
    if not np.isfinite(exposure_s) or exposure_s <= 0:
        raise InputError(f"exposure_s: expected a positive exposure, got {exposure_s}")
    settings = {"light_id": light_id, "view_id": view_id, "band_nm": band_nm, "tilt_deg": tilt_deg}
    return {
        "camera": camera,
        "kind": kind,
        "exposure_s": float(exposure_s),
        **{name: value for name, value in settings.items() if value is not None},
    }


def dark_series(
    camera: str, exposures_s: Iterable[float], frames_per_exposure: int = 50
) -> list[dict[str, Any]]:
    """Dark frames: ``frames_per_exposure`` per exposure time, shutter closed (thesis 3.3)."""
    if frames_per_exposure < 1:
        raise InputError("frames_per_exposure: expected at least one frame")
    return [
        plan_step(camera, "dark", t, light_id=NO_LIGHT)
        for t in exposures_s
        for _ in range(frames_per_exposure)
    ]


def response_curve_series(
    camera: str, exposures_s: Iterable[float], *, light_id: int = 0
) -> list[dict[str, Any]]:
    """One frame of a static scene per exposure time, for the response curve (Robertson)."""
    return [plan_step(camera, "oecf", t, light_id=light_id) for t in exposures_s]


def gonio_sample_run(
    camera: str,
    view_ids: Iterable[int],
    band_centres_nm: Iterable[float],
    band_exposures_s: Iterable[float],
) -> list[dict[str, Any]]:
    """Per direction pair (``view_id``), per band: tune the filter, expose (thesis 4.1.1)."""
    bands = list(band_centres_nm)
    exposures = list(band_exposures_s)
    if len(bands) != len(exposures):
        raise InputError(f"band_exposures_s: expected {len(bands)} exposures, got {len(exposures)}")
    return [
        plan_step(camera, "sample", t, view_id=int(view), band_nm=float(band), light_id=0)
        for view in view_ids
        for band, t in zip(bands, exposures, strict=True)
    ]


def white_reference_run(
    camera: str, band_centres_nm: Iterable[float], band_exposures_s: Iterable[float]
) -> list[dict[str, Any]]:
    """The white standard through every band before a run, for the factors F'_lambda (3.3)."""
    return [
        plan_step(camera, "white", t, band_nm=float(band), light_id=0)
        for band, t in zip(band_centres_nm, band_exposures_s, strict=True)
    ]


def chart_photographs(
    camera: str, exposures_s: Iterable[float], light_ids: Iterable[int]
) -> list[dict[str, Any]]:
    """Colour-chart photographs, one per light and exposure (thesis 9.3)."""
    return [
        plan_step(camera, "chart", t, light_id=int(light))
        for light in light_ids
        for t in exposures_s
    ]


def plan_start_times_s(
    plan: list[dict[str, Any]], *, per_frame_overhead_s: float = 0.13, per_view_move_s: float = 6.0
) -> np.ndarray:
    """When each step's exposure starts, in seconds from the session start: moves to a new view,
    then exposure plus switching/download per frame (thesis 4.1.1). Fixed by the plan alone, so a
    resumed session sees the same lamp phase at every step as an uninterrupted one."""
    starts, clock, view = [], 0.0, None
    for step in plan:
        step_view = step.get("view_id", NO_VIEW)
        if step_view != NO_VIEW and step_view != view:
            clock += per_view_move_s
            view = step_view
        starts.append(clock)
        clock += float(step["exposure_s"]) + per_frame_overhead_s
    return np.array(starts)


def estimate_duration_s(
    plan: list[dict[str, Any]], *, per_frame_overhead_s: float = 0.13, per_view_move_s: float = 6.0
) -> float:
    """Dry-run duration: exposures, per-frame switching/download, and a move per new view."""
    starts = plan_start_times_s(
        plan, per_frame_overhead_s=per_frame_overhead_s, per_view_move_s=per_view_move_s
    )
    return float(starts[-1] + float(plan[-1]["exposure_s"]) + per_frame_overhead_s)
