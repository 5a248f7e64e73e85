"""The LED dome's capture procedures (thesis 10.2-10.4) as plans, and their timing.

Two programs, each a list of steps (one frame each, :func:`hwbridge.plans.plan_step`) stored in
the capture store (layout: :mod:`hwbridge.dome_layout`):

- :func:`dome_calibration`: dark frames of the spectral camera, ``dark_frames`` (thesis 10.3:
  200) per exposure time it uses, and of the RGB cameras per exposure time they use; the response
  series of a colour checker under the calibration LED (the spectral camera in one band, thesis
  10.3, Eq. 10.4-10.8; the RGB cameras for Robertson's curve); every RGB camera's HDR set of a
  second chart under the same LED (with the colour checker, the cameras' spectral responses by
  the method of chapter 9); the white standard under every LED
  of the run (every RGB camera's HDR set and the spectral camera's reference band: the
  irradiance each LED gives, as each camera sees it) and under the calibration LED through every
  band (the sensitivity :math:`E_\\lambda`, 10.3); a checkerboard target, flat and tilted on a
  wedge at several stage positions, with all LEDs on, for the cameras' intrinsics and extrinsics
  (geometric calibration, which the thesis leaves out of scope).
- :func:`dome_run`: per stage position an alignment frame of every camera with all LEDs on
  (10.2.2: the sample holder detected with sub-pixel accuracy), then per LED every RGB camera's
  HDR exposure set (10.4: 50, 186, 666, 2500 ms) and the spectral camera's bands that the band
  schedule (:mod:`recon.scheduling.dome_schedule`) assigns to that LED: LED ``k`` of the run,
  counted over the stage positions, gets schedule image ``k mod n_images``.

The RGB cameras and the spectral camera expose in parallel (10.2.2: "the RGB and the spectral
camera system are operated in parallel"): :func:`dome_start_times_s` times a plan as slots of
consecutive steps that share stage position, light, kind and target tilt; within a slot every
camera takes its frames one after the other (exposure plus its read-out, for the spectral
camera the filter switch too), the cameras side by side, and the slot ends with its slowest
camera. A new stage position costs a turn of the stage, a new light the switching of the LEDs.

References
----------
- The thesis, section 10.2.2 (24 stage positions of 15 degrees, an image with several LEDs on
  per position, then the LEDs one by one, cameras in parallel), 10.3 (200 dark frames per
  exposure time, the response series, the white reference lit by the LEDs), 10.4 (the HDR set,
  :math:`t_\\lambda`, the band schedule) and 4.1.1 (130 ms filter switching and download per
  spectral image).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hwbridge.dome_layout import ALL_LEDS
from hwbridge.errors import InputError
from hwbridge.plans import dark_series, plan_step
from hwbridge.schema import NO_LIGHT, NO_VIEW

__all__ = [
    "DomeCameraIds",
    "DomeExposures",
    "DomeTiming",
    "dome_calibration",
    "dome_duration_s",
    "dome_run",
    "dome_start_times_s",
]


@dataclass(frozen=True)
class DomeCameraIds:
    """The cameras of a dome plan: ``rgb`` (ids of the RGB cameras used) and ``spectral``."""

    rgb: tuple[str, ...]
    spectral: str

    def __post_init__(self) -> None:
        if not self.rgb:
            raise InputError("rgb: expected at least one RGB camera")
        if len(set(self.rgb)) != len(self.rgb) or self.spectral in self.rgb:
            raise InputError(f"cameras: expected distinct ids, got {self.rgb + (self.spectral,)}")

    @property
    def all(self) -> tuple[str, ...]:
        return (*self.rgb, self.spectral)


@dataclass(frozen=True)
class DomeExposures:
    """Exposure times of a dome plan, in seconds.

    Attributes
    ----------
    rgb_hdr_s
        The RGB cameras' HDR set per image (thesis 10.4: 0.05, 0.186, 0.666, 2.5).
    bands_nm, band_s
        The spectral camera's bands and their exposures :math:`t_\\lambda`.
    schedule
        Per schedule image, the indices into ``bands_nm`` the spectral camera exposes meanwhile.
    all_leds_s
        Per camera, the exposure of frames with every LED on (alignment and geometric frames).
    rgb_series_s, spectral_series_s
        The response series of the RGB cameras and of the spectral camera.
    reference_band_nm
        The band of the spectral camera's response series, per-LED white and all-LED frames.
    """

    rgb_hdr_s: tuple[float, ...]
    bands_nm: tuple[float, ...]
    band_s: tuple[float, ...]
    schedule: tuple[tuple[int, ...], ...]
    all_leds_s: Mapping[str, float]
    rgb_series_s: tuple[float, ...] = ()
    spectral_series_s: tuple[float, ...] = ()
    reference_band_nm: float = 550.0

    def __post_init__(self) -> None:
        if len(self.bands_nm) != len(self.band_s) or not self.bands_nm:
            raise InputError(
                f"band_s: expected one exposure per band ({len(self.bands_nm)}), got "
                f"{len(self.band_s)}"
            )
        if not self.rgb_hdr_s:
            raise InputError("rgb_hdr_s: expected at least one RGB exposure")
        scheduled = sorted({band for image in self.schedule for band in image})
        if scheduled != list(range(len(self.bands_nm))):
            raise InputError(
                f"schedule: expected every band index 0..{len(self.bands_nm) - 1} in some image, "
                f"got {scheduled}"
            )
        if self.reference_band_nm not in self.bands_nm:
            raise InputError(
                f"reference_band_nm: {self.reference_band_nm} nm is not among the bands"
            )

    def band_exposure_s(self, band_nm: float) -> float:
        return float(self.band_s[list(self.bands_nm).index(band_nm)])


@dataclass(frozen=True)
class DomeTiming:
    """What a dome capture spends besides exposing: ``stage_move_s`` per new stage position,
    ``led_switch_s`` per new light, ``frame_overhead_s`` per frame of each camera (read-out;
    for the spectral camera the filter switch and download)."""

    stage_move_s: float
    led_switch_s: float
    frame_overhead_s: Mapping[str, float]


def _spectral_step(
    cameras: DomeCameraIds,
    exposures: DomeExposures,
    kind: str,
    exposure_s: float,
    band_nm: float | None = None,
    *,
    light_id: int | None = None,
    view_id: int | None = None,
    tilt_deg: float | None = None,
) -> dict[str, Any]:
    band = exposures.reference_band_nm if band_nm is None else band_nm
    return plan_step(
        cameras.spectral,
        kind,
        exposure_s,
        band_nm=float(band),
        light_id=light_id,
        view_id=view_id,
        tilt_deg=tilt_deg,
    )


def _hdr_sets(
    cameras: DomeCameraIds, exposures: DomeExposures, kind: str, *, view_id: int, light_id: int
) -> list[dict[str, Any]]:
    """Every RGB camera's HDR set, camera after camera."""
    return [
        plan_step(camera, kind, t, view_id=view_id, light_id=light_id)
        for camera in cameras.rgb
        for t in exposures.rgb_hdr_s
    ]


def _all_leds_frames(
    cameras: DomeCameraIds,
    exposures: DomeExposures,
    kind: str,
    *,
    view_id: int,
    tilt_deg: float | None = None,
) -> list[dict[str, Any]]:
    """One frame of every camera with every LED on (the spectral camera in the reference band)."""
    rgb = [
        plan_step(
            camera,
            kind,
            exposures.all_leds_s[camera],
            light_id=ALL_LEDS,
            view_id=view_id,
            tilt_deg=tilt_deg,
        )
        for camera in cameras.rgb
    ]
    spectral = exposures.all_leds_s[cameras.spectral]
    spectral_step = _spectral_step(
        cameras, exposures, kind, spectral, light_id=ALL_LEDS, view_id=view_id, tilt_deg=tilt_deg
    )
    return [*rgb, spectral_step]


def _check_ids(name: str, values: Sequence[int], count: int | None = None) -> list[int]:
    ids = [int(value) for value in values]
    if not ids or len(set(ids)) != len(ids) or min(ids) < 0:
        raise InputError(f"{name}: expected distinct non-negative indices, got {ids}")
    if count is not None and max(ids) >= count:
        raise InputError(f"{name}: expected indices below {count}, got {max(ids)}")
    return ids


def dome_run(
    cameras: DomeCameraIds,
    exposures: DomeExposures,
    *,
    stage_positions: Sequence[int],
    leds: Sequence[int],
) -> list[dict[str, Any]]:
    """The measurement of one material (thesis 10.2.2, 10.4; module docstring).

    Parameters
    ----------
    cameras
        The cameras used.
    exposures
        The HDR set, the bands, their exposures and schedule, the all-LED exposures.
    stage_positions
        Stage positions (``view_id``, indices into the rig's stage angles), in capture order.
    leds
        LEDs (``light_id``), switched on one by one in this order at every stage position.

    Returns
    -------
    list of dict
        Per stage position: the alignment frames (``kind="alignment"``, ``light_id``
        :data:`~hwbridge.dome_layout.ALL_LEDS`), then per LED the RGB cameras' HDR sets and the
        scheduled spectral bands (``kind="sample"``).
    """
    positions = _check_ids("stage_positions", stage_positions)
    lights = _check_ids("leds", leds)
    plan: list[dict[str, Any]] = []
    image = 0
    for view in positions:
        plan += _all_leds_frames(cameras, exposures, "alignment", view_id=view)
        for led in lights:
            plan += _hdr_sets(cameras, exposures, "sample", view_id=view, light_id=led)
            for band in exposures.schedule[image % len(exposures.schedule)]:
                plan.append(
                    _spectral_step(
                        cameras,
                        exposures,
                        "sample",
                        exposures.band_s[band],
                        exposures.bands_nm[band],
                        view_id=view,
                        light_id=led,
                    )
                )
            image += 1
    return plan


def _distinct(times: Sequence[float]) -> list[float]:
    return sorted({float(t) for t in times})


def dome_calibration(
    cameras: DomeCameraIds,
    exposures: DomeExposures,
    *,
    leds: Sequence[int],
    calibration_led: int,
    geometric_views: Sequence[tuple[int, float]],
    dark_frames: int = 200,
    rgb_dark_frames: int = 16,
) -> list[dict[str, Any]]:
    """The calibration of the dome's cameras (thesis 10.3; module docstring).

    Parameters
    ----------
    cameras, exposures
        As for :func:`dome_run`; ``exposures`` must have both response series.
    leds
        The LEDs of the run: the white standard is photographed under each.
    calibration_led
        The LED of the response series and of the white standard through every band.
    geometric_views
        ``(stage position, wedge tilt in degrees)`` of each geometric frame set.
    dark_frames
        Dark frames of the spectral camera per exposure time it uses (thesis 10.3: 200): its
        band exposures, response series and all-LED exposure.
    rgb_dark_frames
        Dark frames of each RGB camera per exposure time it uses (its HDR set and all-LED
        exposure).

    Returns
    -------
    list of dict
        Dark frames, response series (``oecf``, of the colour checker), every RGB camera's HDR
        set of the second chart (``chart``), white frames, geometric frames, in this order.
    """
    lights = _check_ids("leds", leds)
    if not exposures.rgb_series_s or not exposures.spectral_series_s:
        raise InputError("exposures: the calibration needs both response series")
    if not geometric_views:
        raise InputError("geometric_views: expected at least one stage position and tilt")
    spectral_times = _distinct(
        [*exposures.band_s, *exposures.spectral_series_s, exposures.all_leds_s[cameras.spectral]]
    )
    plan = dark_series(cameras.spectral, spectral_times, dark_frames)
    for camera in cameras.rgb:
        times = _distinct([*exposures.rgb_hdr_s, exposures.all_leds_s[camera]])
        plan += dark_series(camera, times, rgb_dark_frames)
    lit = {"view_id": 0, "light_id": int(calibration_led)}
    plan += [
        _spectral_step(cameras, exposures, "oecf", t, **lit) for t in exposures.spectral_series_s
    ]
    plan += [
        plan_step(camera, "oecf", t, **lit)
        for camera in cameras.rgb
        for t in exposures.rgb_series_s
    ]
    plan += _hdr_sets(cameras, exposures, "chart", **lit)
    reference_s = exposures.band_exposure_s(exposures.reference_band_nm)
    for led in lights:
        plan += _hdr_sets(cameras, exposures, "white", view_id=0, light_id=led)
        plan.append(
            _spectral_step(cameras, exposures, "white", reference_s, view_id=0, light_id=led)
        )
    plan += [
        _spectral_step(cameras, exposures, "white", t, band, **lit)
        for band, t in zip(exposures.bands_nm, exposures.band_s, strict=True)
    ]
    for view, tilt in geometric_views:
        plan += _all_leds_frames(
            cameras, exposures, "geometric", view_id=int(view), tilt_deg=float(tilt)
        )
    return plan


def _slot_key(step: dict[str, Any]) -> tuple[Any, ...]:
    return (
        step.get("view_id", NO_VIEW),
        step.get("light_id", NO_LIGHT),
        step["kind"],
        step.get("tilt_deg"),
    )


def _timeline(plan: list[dict[str, Any]], timing: DomeTiming) -> tuple[np.ndarray, float]:
    """Exposure starts of every step and the end of the plan (module docstring)."""
    unknown = sorted({step["camera"] for step in plan} - set(timing.frame_overhead_s))
    if unknown:
        raise InputError(f"timing: no frame overhead for cameras {unknown}")
    starts = np.empty(len(plan))
    clock, slot, view, light = 0.0, None, None, NO_LIGHT
    cameras: dict[str, float] = {}
    for index, step in enumerate(plan):
        key = _slot_key(step)
        if key != slot:
            clock = max(cameras.values(), default=clock)
            cameras, slot = {}, key
            if key[0] != NO_VIEW and key[0] != view:
                clock += timing.stage_move_s
                view = key[0]
            if key[1] != NO_LIGHT and key[1] != light:
                clock += timing.led_switch_s
                light = key[1]
        start = cameras.get(step["camera"], clock)
        starts[index] = start
        cameras[step["camera"]] = (
            start + float(step["exposure_s"]) + timing.frame_overhead_s[step["camera"]]
        )
    return starts, max(cameras.values(), default=clock)


def dome_start_times_s(plan: list[dict[str, Any]], timing: DomeTiming) -> np.ndarray:
    """When each step's exposure starts, in seconds from the start, cameras in parallel
    (module docstring). Fixed by the plan, so a resumed capture gets the same times.

    Examples
    --------
    >>> timing = DomeTiming(3.0, 0.0, {"rgb00": 0.1, "spectral": 0.1})
    >>> plan = [
    ...     {"camera": "rgb00", "kind": "sample", "exposure_s": 1.0, "view_id": 0, "light_id": 5},
    ...     {"camera": "rgb00", "kind": "sample", "exposure_s": 2.0, "view_id": 0, "light_id": 5},
    ...     {"camera": "spectral", "kind": "sample", "exposure_s": 4.0, "view_id": 0,
    ...      "light_id": 5},
    ...     {"camera": "rgb00", "kind": "sample", "exposure_s": 1.0, "view_id": 0, "light_id": 6},
    ... ]
    >>> dome_start_times_s(plan, timing).tolist()
    [3.0, 4.1, 3.0, 7.1]
    """
    return _timeline(plan, timing)[0]


def dome_duration_s(plan: list[dict[str, Any]], timing: DomeTiming) -> float:
    """How long ``plan`` takes, cameras in parallel (module docstring)."""
    if not plan:
        raise InputError("plan: expected at least one step")
    return _timeline(plan, timing)[1]
