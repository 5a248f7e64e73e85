"""The dome's LEDs on the sample's plate: the irradiance of a point light and its scale.

An LED 0.75 m away lights the plate with the irradiance
:math:`E(x) = I \\cos\\theta / r^2 = I (p_z - x_z) / \\lVert p - x \\rVert^3`
(:func:`led_irradiance`, per unit intensity :math:`I`): over a 4 cm sample it changes by a few
percent, with the distance and the angle of incidence.
The calibration measures, per LED and camera, the scale of that field (:func:`field_scale`: the
white standard's linear values over the field, least squares) at stage position 0; at any
other stage position the sample's texel ``x`` lies at :math:`R_z(\\alpha) x` in the world, where
the field is evaluated again. The white reference under the same LED thus divides out
:math:`\\cos\\theta_i`, the LED's intensity and its distance for every texel (thesis 10.3:
"dividing the linearized camera response by the LED spectrum"; 10.2.2: light directions that
vary over the sample).

References
----------
- The thesis, sections 10.2.2 and 10.3.
"""

from __future__ import annotations

import numpy as np

from recon.errors import InputError

__all__ = ["field_scale", "led_irradiance"]


def led_irradiance(points_m: np.ndarray, led_position_m: np.ndarray) -> np.ndarray:
    """Irradiance per unit intensity (1/m^2) on a horizontal plane at ``points_m`` ``(..., 3)``
    (world frame) from a point light at ``led_position_m`` ``(3,)``.

    Examples
    --------
    >>> float(led_irradiance(np.zeros(3), np.array([0.0, 0.0, 2.0])))
    0.25
    """
    offset = np.asarray(led_position_m, np.float64) - np.asarray(points_m, np.float64)
    distance = np.linalg.norm(offset, axis=-1)
    if np.any(offset[..., 2] <= 0):
        raise InputError("led_position_m: expected a light above the plate")
    return offset[..., 2] / distance**3


def field_scale(values: np.ndarray, field: np.ndarray) -> np.ndarray:
    """Least-squares scale ``k`` per channel of ``values`` ``(..., C)`` against ``field``
    ``(...)``: :math:`\\min_k \\sum (v - k\\, E)^2` over the finite values.

    Examples
    --------
    >>> field_scale(np.array([[2.0], [4.0]]), np.array([1.0, 2.0])).tolist()
    [2.0]
    """
    values = np.asarray(values, np.float64)
    field = np.broadcast_to(np.asarray(field, np.float64)[..., None], values.shape)
    finite = np.isfinite(values) & np.isfinite(field)
    if not np.all(finite.sum(axis=tuple(range(values.ndim - 1)))):
        raise InputError("values: a channel has no finite value to scale")
    numerator = np.where(finite, values * field, 0.0).reshape(-1, values.shape[-1]).sum(0)
    denominator = np.where(finite, field**2, 0.0).reshape(-1, values.shape[-1]).sum(0)
    return numerator / denominator
