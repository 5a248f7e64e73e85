"""The LED dome's capture store: what its groups, index fields and metadata hold.

A dome capture (thesis 10.2-10.4) is written into the same capture store as the
gonioreflectometer's (:class:`hwbridge.store.CaptureStore`: one chunk per frame, a checksum per
chunk, one writer, kill-safe resume). This module names the parts of it that the dome's
processing reads, and its docstring is the layout's reference (also ``ARCHITECTURE.md``,
"Stores").

Groups, one per camera
----------------------
``frames/<camera>``
    uint16 raw frames ``(n, H, W)``, ``H = W`` = the rig's ``window_px``. ``rgb00`` ... ``rgb10``
    (:func:`rgb_camera_id`) are the RGB cameras of the arc by arc index, ``rgb00`` at the top,
    ``rgb10`` at 75 degrees from it (RGGB Bayer mosaic, raw); ``spectral``
    (:data:`SPECTRAL_CAMERA`) is the monochrome camera behind the tunable filter. A reduced
    capture keeps the arc indices of the RGB cameras it uses.
``index/<camera>/<field>``
    One entry per frame:

    - ``kind``: ``dark`` (shutter closed), ``oecf`` (exposure series of the colour checker for
      the response curve), ``chart`` (a second chart, the RGB cameras' HDR sets: with the
      colour checker, their spectral responses), ``white`` (the white standard), ``geometric``
      (the checkerboard target), ``alignment`` (the material, all LEDs on), ``sample`` (the
      material, one LED on);
      :data:`DOME_KINDS`;
    - ``view_id``: the stage position, an index into the geometry's ``stage_angles_deg``;
      :data:`~hwbridge.schema.NO_VIEW` (-1) for dark frames;
    - ``light_id``: the LED, an index into the geometry's ``led_positions_m``;
      :data:`~hwbridge.schema.NO_LIGHT` (-1) for dark frames, :data:`ALL_LEDS` (-2) for
      alignment and geometric frames;
    - ``band_nm``: the tunable filter's band of a ``spectral`` frame (NaN for RGB frames);
    - ``exposure_s``;
    - ``status``: ``ok``, or ``ok after ...`` naming the device faults retried for the frame;
    - ``timestamp``: wall-clock time, the one field in which identical captures differ;
    - ``pose``: unused (NaN).
``progress``
    One flag per plan step, set once the step's frame and index are written.

Attributes
----------
``plan``
    One :class:`~hwbridge.schema.PlanStep` per step: ``camera``, ``kind``, ``exposure_s``, and
    where set ``view_id``, ``light_id``, ``band_nm`` and ``tilt_deg`` (the wedge under the
    checkerboard of a geometric frame). Frame ``k`` of ``frames/<camera>`` is the ``k``-th step
    naming ``<camera>`` (:func:`camera_steps`).
``rig``
    A :class:`~hwbridge.schema.DomeRigAttrs`: the program's settings, the exposure plan, the
    spectra processing needs and the ``geometry`` (:class:`~hwbridge.schema.DomeGeometry`:
    stage angles, LED positions, every camera, the holder's print and the checkerboard) in
    metres, in the world frame (origin at the sample centre on the stage, z up; the sample
    frame is the world turned about z by the stage angle).

The programs' order of steps and their timing are in :mod:`hwbridge.dome_plans`.
"""

from __future__ import annotations

from collections.abc import Sequence

from hwbridge.schema import PlanStep

__all__ = [
    "ALL_LEDS",
    "DOME_KINDS",
    "SPECTRAL_CAMERA",
    "camera_steps",
    "rgb_camera_id",
]

SPECTRAL_CAMERA = "spectral"
"""Camera id of the monochrome camera behind the tunable filter."""

ALL_LEDS = -2
"""``light_id`` of frames with every LED on (alignment and geometric frames)."""

DOME_KINDS = ("dark", "oecf", "chart", "white", "geometric", "alignment", "sample")
"""Frame kinds of dome stores (module docstring)."""


def rgb_camera_id(arc_index: int) -> str:
    """Camera id of the RGB camera at ``arc_index`` on the arc (0 = top): ``rgb00`` ...

    Examples
    --------
    >>> rgb_camera_id(6)
    'rgb06'
    """
    return f"rgb{int(arc_index):02d}"


def camera_steps(plan: Sequence[PlanStep], camera: str) -> list[int]:
    """The plan steps of ``camera`` in frame order: frame ``k`` of ``frames/<camera>`` is step
    ``camera_steps(plan, camera)[k]``.

    Examples
    --------
    >>> plan = [PlanStep(camera=c, kind="dark", exposure_s=1.0) for c in ("a", "b", "a")]
    >>> camera_steps(plan, "a")
    [0, 2]
    """
    return [step for step, settings in enumerate(plan) if settings.camera == camera]
