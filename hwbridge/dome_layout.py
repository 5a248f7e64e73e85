"""The LED dome's capture store: what its groups, index fields and metadata hold.

A dome capture (thesis 10.2-10.4) is written into the same capture store as the
gonioreflectometer's (:class:`hwbridge.store.CaptureStore`: one chunk per frame, a checksum per
chunk, one writer, kill-safe resume). This module names the parts of it that the dome's
processing reads, and its docstring is the layout's reference (also ``ARCHITECTURE.md``,
"Stores").

Groups, one per camera
----------------------
``frames/<camera>``
    uint16 raw frames ``(n, H, W)``, ``H = W = rig["window_px"]``. ``rgb00`` ... ``rgb10``
    (:func:`rgb_camera_id`) are the RGB cameras of the arc by arc index, ``rgb00`` at the top,
    ``rgb10`` at 75 degrees from it (RGGB Bayer mosaic, raw); ``spectral``
    (:data:`SPECTRAL_CAMERA`) is the monochrome camera behind the tunable filter. A reduced
    capture keeps the arc indices of the RGB cameras it uses.
``index/<camera>/<field>``
    One entry per frame:

    - ``kind``: ``dark`` (shutter closed), ``oecf`` (exposure series of the colour checker for
      the response curve), ``white`` (the white standard), ``geometric`` (the checkerboard
      target), ``alignment`` (the material, all LEDs on), ``sample`` (the material, one LED on);
      :data:`DOME_KINDS`;
    - ``view_id``: the stage position, an index into ``rig["geometry"]["stage_angles_deg"]``;
      -1 for dark frames;
    - ``light_id``: the LED, an index into ``rig["geometry"]["led_positions_m"]``;
      :data:`NO_LIGHT` (-1) for dark frames, :data:`ALL_LEDS` (-2) for alignment and geometric
      frames;
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
    One dict per step: ``camera``, ``kind``, ``exposure_s``, and where set ``view_id``,
    ``light_id``, ``band_nm`` and ``tilt_deg`` (the wedge under the checkerboard of a geometric
    frame). Frame ``k`` of ``frames/<camera>`` is the ``k``-th step naming ``<camera>``
    (:func:`camera_steps`).
``rig``
    - ``rig`` (``"dome"``), ``program`` (``dome-calibration`` or ``dome-run``), ``material``
      (the run's), ``texels``, ``spp``, ``window_px``, ``pixels`` (across the 0.2 m field),
      ``stage_positions``, ``leds``, ``rgb_cameras`` (the reduced size's counts);
    - ``rgb_exposures_s`` (the HDR set), ``bands_nm``, ``band_exposures_s`` (one per band),
      ``band_schedule`` (per schedule image, the indices into ``bands_nm`` exposed meanwhile;
      LED ``k`` of the run, counted over stage positions, gets image ``k mod len``),
      ``calibration_led`` (the LED of the response series and the band-wise white frames),
      ``led_current_ma`` (the drive current of every lit frame);
    - ``led_spectrum`` and ``white_reflectance``: ``{"wavelengths_nm": [...], "values": [...]}``,
      the LEDs' radiant intensity at that current (W sr^-1 nm^-1) and the white standard's
      reflectance factor; ``rgb_response`` likewise with three rows of values (R, G, B): the RGB
      cameras' relative spectral response, as their characterization gives it (thesis chapter 9);
    - ``sample_size_m`` (a run): the side of the material's square, centred on the plate;
    - ``geometry`` (metres, world frame: origin at the sample centre on the stage, z up; the
      sample frame is the world turned about z by the stage angle):

      - ``stage_angles_deg``: angle of every stage position;
      - ``led_positions_m``: every LED;
      - ``cameras``: per camera, ``role`` (``rgb``/``spectral``), ``definition`` (model in
        ``scenes/cameras``), ``mosaic``, ``arc_index`` (RGB), ``position_m``,
        ``rotation_world_to_camera`` and ``camera_matrix`` (OpenCV conventions: x right, y
        down, z forward, pixel centres at integer coordinates, for the stored window),
        ``distortion`` (OpenCV's five coefficients), ``bit_depth``, ``frame_px`` (rows,
        columns), ``pixel_pitch_m`` at the rig centre and
        ``marker_corners_xy`` (per stage position the capture uses, the nominal image points of
        the holder's registration corners);
      - ``holder``: ``registration_corners_m`` ``(4, 3)`` in the sample frame, in the order of
        the texture's corners ``(0, 0), (1, 0), (1, 1), (0, 1)``, ``print_inner_half_m``,
        ``print_outer_half_m`` and ``opening_half_m`` (the material's square);
      - ``geometric_target``: ``squares`` and ``inner_corners`` (columns, rows),
        ``square_m``, ``corners_m`` (the inner corners in the target frame, z = 0, row by row
        as OpenCV lists them) and ``target_to_sample``: per ``tilt_deg`` (as a string) the 4x4
        pose of the target on its wedge in the sample frame.

The programs' order of steps and their timing are in :mod:`hwbridge.dome_plans`.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "ALL_LEDS",
    "DOME_KINDS",
    "NO_LIGHT",
    "SPECTRAL_CAMERA",
    "camera_steps",
    "rgb_camera_id",
]

SPECTRAL_CAMERA = "spectral"
"""Camera id of the monochrome camera behind the tunable filter."""

NO_LIGHT = -1
"""``light_id`` of frames without light (dark frames)."""

ALL_LEDS = -2
"""``light_id`` of frames with every LED on (alignment and geometric frames)."""

DOME_KINDS = ("dark", "oecf", "white", "geometric", "alignment", "sample")
"""Frame kinds of dome stores (module docstring)."""


def rgb_camera_id(arc_index: int) -> str:
    """Camera id of the RGB camera at ``arc_index`` on the arc (0 = top): ``rgb00`` ...

    Examples
    --------
    >>> rgb_camera_id(6)
    'rgb06'
    """
    return f"rgb{int(arc_index):02d}"


def camera_steps(plan: list[dict[str, Any]], camera: str) -> list[int]:
    """The plan steps of ``camera`` in frame order: frame ``k`` of ``frames/<camera>`` is step
    ``camera_steps(plan, camera)[k]``.

    Examples
    --------
    >>> camera_steps([{"camera": "a"}, {"camera": "b"}, {"camera": "a"}], "a")
    [0, 2]
    """
    return [step for step, settings in enumerate(plan) if settings["camera"] == camera]
