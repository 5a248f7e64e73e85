"""Where a shape, a light or a sensor sits in a Mitsuba scene: the ``to_world`` transforms of
scene entries.

Each function returns Mitsuba's ``ScalarTransform4f`` in the active variant; ``@`` chains them,
the right-hand one applied first: ``translate(t) @ rotate(axis, angle) @ scale(s)`` scales,
then rotates, then translates. Rooms above the renderer place their entries with these instead
of importing Mitsuba.
"""

from __future__ import annotations

from collections.abc import Sequence

import mitsuba as mi

from twin.render.variant import activate

__all__ = ["look_at", "matrix", "rotate", "scale", "translate"]


def look_at(
    *, origin: Sequence[float], target: Sequence[float], up: Sequence[float]
) -> mi.ScalarTransform4f:
    """An entry at ``origin`` whose local +z points at ``target``, local +y towards ``up``
    (a sensor, a spot light, a disk facing a point), metres in the world frame."""
    activate()
    return mi.ScalarTransform4f.look_at(origin=origin, target=target, up=up)


def translate(offset_m: Sequence[float]) -> mi.ScalarTransform4f:
    """A shift by ``offset_m`` ``(x, y, z)``, metres."""
    activate()
    return mi.ScalarTransform4f.translate(offset_m)


def rotate(axis: Sequence[float], angle_deg: float) -> mi.ScalarTransform4f:
    """A rotation by ``angle_deg`` about ``axis`` (right-handed)."""
    activate()
    return mi.ScalarTransform4f.rotate(axis, angle_deg)


def scale(factor: float | Sequence[float]) -> mi.ScalarTransform4f:
    """A scaling by ``factor``, one for all axes or ``(x, y, z)``."""
    activate()
    return mi.ScalarTransform4f.scale(factor)


def matrix(to_world: Sequence[Sequence[float]]) -> mi.ScalarTransform4f:
    """The transform of a 4 x 4 matrix ``to_world`` (rows; its last column the position, m)."""
    activate()
    return mi.ScalarTransform4f([list(map(float, row)) for row in to_world])
