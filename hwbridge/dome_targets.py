"""Requests to the LED dome's rotation stage and LED array, checked at the door.

The simulated devices (``twin.devices``) and the real drivers (``hwbridge.drivers``) check a
request the same way, so they refuse the same requests with the same one-line
:class:`~hwbridge.errors.InputError`. The dome (thesis 10.2.2) turns its sample in 24 steps
of 15 deg and switches its 198 LEDs on one at a time, all of them for the alignment frames.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from hwbridge.errors import InputError

__all__ = ["check_current_ma", "led_pattern", "single_led", "stage_angle_deg"]


def stage_angle_deg(
    target: Mapping[str, float],
    *,
    step_deg: float,
    range_deg: tuple[float, float],
    name: str,
) -> float:
    """The stage angle a ``Positioner.set`` target asks for.

    Parameters
    ----------
    target
        ``{"angle_deg": a}`` for an angle, or ``{"view_id": k}`` for stage position ``k`` of a
        capture plan (:func:`hwbridge.dome_plans.dome_run`), which is ``k * step_deg``.
    step_deg
        The turn between two stage positions (15 deg on the dome).
    range_deg
        The lowest and highest angle the stage may be sent to, both included.
    name
        The device's name, for the error message.

    Returns
    -------
    float
        The angle in degrees.

    Raises
    ------
    InputError
        A target with other keys than one of those two, or an angle outside ``range_deg``.
    """
    if set(target) == {"angle_deg"}:
        angle = float(target["angle_deg"])
    elif set(target) == {"view_id"}:
        angle = int(target["view_id"]) * step_deg
    else:
        raise InputError(
            f"{name}: expected a target {{'angle_deg': a}} or {{'view_id': k}}, got "
            f"{sorted(target)}"
        )
    low, high = range_deg
    if not low <= angle <= high:  # NaN fails too
        raise InputError(
            f"{name}: angle {angle:g} deg is outside the stage's range {low:g}-{high:g} deg"
        )
    return angle


def led_pattern(pattern: object, count: int, name: str) -> np.ndarray:
    """``pattern`` as a boolean array of ``count`` LEDs, or a :class:`InputError`."""
    pattern = np.asarray(pattern)
    if pattern.shape != (count,) or not (pattern.dtype == bool or np.isin(pattern, (0, 1)).all()):
        raise InputError(
            f"{name}: expected an on/off pattern of {count} LEDs, got shape {pattern.shape} "
            f"of {pattern.dtype}"
        )
    return pattern.astype(bool)


def single_led(led: int, count: int, name: str) -> np.ndarray:
    """The pattern with LED ``led`` alone on, or a :class:`InputError`."""
    if not 0 <= led < count:
        raise InputError(f"{name}: LED {led} is not in 0..{count - 1}")
    pattern = np.zeros(count, bool)
    pattern[led] = True
    return pattern


def check_current_ma(current_ma: float, current_range_ma: tuple[float, float], name: str) -> float:
    """``current_ma`` if it is a positive current within ``current_range_ma`` (both included)."""
    low, high = current_range_ma
    if not current_ma > 0:  # NaN fails too
        raise InputError(
            f"{name}: expected a positive LED current, got {current_ma} mA (switch LEDs off with "
            "an all-off pattern)"
        )
    if not low <= current_ma <= high:
        raise InputError(
            f"{name}: current {current_ma:g} mA is outside the driver's range {low:.4g}-{high:g} mA"
        )
    return float(current_ma)
