"""The placement of scene entries (twin.render.transforms): Mitsuba's transforms, chained with
``@``, the right-hand one applied first."""

import numpy as np

from twin.render.transforms import look_at, rotate, scale, translate


def test_a_chain_scales_then_rotates_then_translates():
    placed = translate([1.0, 0.0, 0.0]) @ rotate([0.0, 0.0, 1.0], 90.0) @ scale(2.0)
    point = np.array(placed.matrix) @ [1.0, 0.0, 0.0, 1.0]
    np.testing.assert_allclose(point, [1.0, 2.0, 0.0, 1.0], atol=1e-6)


def test_look_at_points_the_local_z_axis_at_the_target():
    placed = look_at(origin=[0.0, 0.0, 2.0], target=[0.0, 0.0, 0.0], up=[0.0, 1.0, 0.0])
    matrix = np.array(placed.matrix)
    np.testing.assert_allclose(matrix @ [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, -1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(matrix @ [0.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(matrix[:3, 3], [0.0, 0.0, 2.0])
