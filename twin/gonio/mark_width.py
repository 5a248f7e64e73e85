"""How wide the holder's registration marks appear in a gonioreflectometer frame, and whether
the registration can find them (thesis 4.1.2).

The registration (:mod:`recon.registration.border`) thresholds the band mean of a pair's frames
and looks for the outer contour of the black print around the sample (the band between
:data:`twin.materials.sample_holder.PRINT_INNER_HALF_M` and ``PRINT_OUTER_HALF_M``, 4 mm wide).
Seen at a view angle :math:`\\theta_v` the print's sides across the tilt shrink by about
:math:`\\cos\\theta_v`, and with few pixels across the camera's 20 cm field such a side is less
than two pixels wide: blurred by the pixels into the paper around it, it no longer forms a dark
contour, and the pair is left unregistered.

:func:`mark_widths_px` predicts, from the rig's geometry alone, each pair's narrowest print side
in pixels (the distance across the side in the image, at the camera's ``pixels`` across its
field); :func:`registration_outlook` turns the widths into the pairs unlikely to register (below
:data:`UNLIKELY_BELOW_PX`), the pairs that may not register (below :data:`MAYBE_BELOW_PX`) and
the smallest ``pixels`` at which every pair's print is at least :data:`MAYBE_BELOW_PX` wide. The
thresholds are calibrated on real captures of the twin (BENCHMARKS.md, "Registration at small
--pixels").
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from twin.gonio.render import gonio_camera, pose_matrix
from twin.materials.sample_holder import PRINT_INNER_HALF_M, PRINT_OUTER_HALF_M
from twin.output_format import format_pairs
from twin.rigs.gonio_kinematics import GonioPose
from twin.rigs.rig_config import GonioConfig

__all__ = [
    "MAYBE_BELOW_PX",
    "UNLIKELY_BELOW_PX",
    "RegistrationOutlook",
    "mark_widths_px",
    "registration_outlook",
]

UNLIKELY_BELOW_PX = 1.3
"""Narrowest print side (pixels) below which a pair is unlikely to register."""
MAYBE_BELOW_PX = 2.1
"""Narrowest print side (pixels) below which a pair may not register."""
_ALONG = np.linspace(-0.8, 0.8, 5)  # points along each side, as fractions of the inner half


def _side_points(half_m: float) -> np.ndarray:
    """Points ``(4, n, 3)`` on the four sides of the print's square of half-size ``half_m``
    (sides +x, +y, -x, -y), in the sample frame on the plate's top."""
    along = _ALONG * PRINT_INNER_HALF_M
    ones = np.full_like(along, half_m)
    zeros = np.zeros_like(along)
    return np.stack(
        [
            np.column_stack([ones, along, zeros]),
            np.column_stack([along, ones, zeros]),
            np.column_stack([-ones, along, zeros]),
            np.column_stack([along, -ones, zeros]),
        ]
    )


def _narrowest_side_px(
    config: GonioConfig, pose: GonioPose, pixels: int, sides: np.ndarray
) -> float:
    """The narrowest width in pixels, across the side, of the print seen at ``pose``; ``sides``:
    the inner and then the outer sides' points (:func:`_side_points`)."""
    matrix = pose_matrix(pose)
    world = sides.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    xy = gonio_camera(config, pose.rail_deg, pixels).project(world).reshape(2, 4, _ALONG.size, 2)
    inner_xy, outer_xy = xy
    along = outer_xy[:, -1] - outer_xy[:, 0]  # (4, 2): each side's direction in the image
    normal = np.column_stack([-along[:, 1], along[:, 0]]) / np.linalg.norm(along, axis=1)[:, None]
    return float(np.abs(np.einsum("snk,sk->sn", inner_xy - outer_xy, normal)).min())


def mark_widths_px(config: GonioConfig, poses: Iterable[GonioPose], pixels: int) -> np.ndarray:
    """The narrowest side of the holder's print, in pixels, in each pair's frame.

    Parameters
    ----------
    config
        The rig (camera on its rail, its field of view).
    poses
        The robot pose of each pair.
    pixels
        Pixels across the camera's field (``--pixels``).

    Returns
    -------
    numpy.ndarray
        ``(n_pairs,)``: the width across the print's narrowest side (its four sides sampled at
        five points each), pixels at the image's scale; a frontal view at 256 px gives about 5.
    """
    sides = np.concatenate([_side_points(PRINT_INNER_HALF_M), _side_points(PRINT_OUTER_HALF_M)])
    return np.array([_narrowest_side_px(config, pose, pixels, sides) for pose in poses], np.float64)


@dataclass(frozen=True)
class RegistrationOutlook:
    """What the marks' widths predict for the registration of a measurement run
    (:func:`registration_outlook`).

    Attributes
    ----------
    narrowest_mark_px
        The narrowest print side over all pairs, pixels.
    unlikely
        The pairs whose print is narrower than :data:`UNLIKELY_BELOW_PX`.
    maybe
        The pairs whose print is from :data:`UNLIKELY_BELOW_PX` up to :data:`MAYBE_BELOW_PX`.
    pixels_registering_every_pair
        The smallest pixels across the field at which every pair's print is
        :data:`MAYBE_BELOW_PX` wide or more; ``None`` when the camera's pixels do not suffice.
    """

    narrowest_mark_px: float
    unlikely: tuple[int, ...]
    maybe: tuple[int, ...]
    pixels_registering_every_pair: int | None

    def summary(self) -> dict[str, object]:
        """The outlook as a dry run prints it: pair lists summarized
        (:func:`twin.output_format.format_pairs`, ``"none"`` when empty)."""
        return {
            "narrowest_mark_px": self.narrowest_mark_px,
            "pairs_unlikely_to_register": _pairs(self.unlikely),
            "pairs_that_may_not_register": _pairs(self.maybe),
            "pixels_registering_every_pair": self.pixels_registering_every_pair,
        }


def _pairs(pairs: tuple[int, ...]) -> str:
    return format_pairs(pairs) if pairs else "none"


def registration_outlook(
    config: GonioConfig, poses: Mapping[int, GonioPose], pixels: int, max_pixels: int
) -> RegistrationOutlook:
    """Which pairs of a measurement run the marks' widths predict not to register.

    Parameters
    ----------
    config, pixels
        As for :func:`mark_widths_px`.
    poses
        The robot pose of each pair, by the pair's number.
    max_pixels
        The most pixels the camera takes across its field.

    Returns
    -------
    RegistrationOutlook
        The pairs unlikely to register, those that may not, and the pixels that register every
        pair.
    """
    pairs = np.array(list(poses), np.int64)
    widths = mark_widths_px(config, poses.values(), pixels)
    narrowest = float(widths.min())
    # Widths grow in proportion to the pixels (the projection's scale); rounding checked.
    enough = max(1, math.ceil(pixels * MAYBE_BELOW_PX / narrowest))
    while narrowest * enough / pixels < MAYBE_BELOW_PX:
        enough += 1
    return RegistrationOutlook(
        narrowest,
        tuple(pairs[widths < UNLIKELY_BELOW_PX].tolist()),
        tuple(pairs[(widths >= UNLIKELY_BELOW_PX) & (widths < MAYBE_BELOW_PX)].tolist()),
        enough if enough <= max_pixels else None,
    )
