"""Gonioreflectometer kinematics: direction pairs to lamp position, rail angle and sample pose.

World frame: origin at the sample centre (the centre of the rail circle), z up. The camera runs
on a half-circle rail in the horizontal plane and looks at the origin from azimuth
:math:`\\alpha`; the lamp stands at one of the rig's fixed positions. The robot orients the sample
holder; its orientation is written as base yaw, tilt of the sample normal from +z and wrist roll
(:math:`R = R_z(\\psi) R_y(\\beta) R_z(\\gamma)`).

For a light direction :math:`l` and view direction :math:`v` in the sample's local frame, the
angle between lamp and camera seen from the sample must equal the angle between :math:`l` and
:math:`v`; that fixes the rail angle, and the rotation that maps :math:`(l, v)` onto the world
lamp and camera directions fixes the sample pose. A lamp on either side of the rail serves the two
mirror-image solutions; with the sample normal kept in the upper half-space (tilt <= 90 deg) each
pair is served by exactly one lamp position, which is why the thesis moves the lamp between two
runs (section 4.1.1: "otherwise a fully circular rail would be necessary").

References
----------
- The thesis, sections 3.2.1 and 4.1.1; Sattler et al. (2003), see ``twin.rigs.hemisphere``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from twin.rigs.hemisphere import angle_between_deg, direction, sattler_directions
from twin.rigs.rig_config import GonioConfig

__all__ = ["GonioPose", "GonioSolution", "forward_directions", "perturbed_pose", "solve_pairs"]


@dataclass(frozen=True)
class GonioPose:
    """Where every axis of the rig stands for one direction pair."""

    lamp_id: str
    rail_deg: float
    yaw_deg: float
    tilt_deg: float
    roll_deg: float
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)  # sample centre off the rig centre

    def rotation(self) -> Rotation:
        """Sample-to-world rotation."""
        return Rotation.from_euler(
            "ZYZ", [self.yaw_deg, self.tilt_deg, self.roll_deg], degrees=True
        )


@dataclass(frozen=True)
class GonioSolution:
    """Poses for requested pairs; ``exact[i]`` is False where the rig could only get close."""

    light_local: np.ndarray  # (n, 3) requested
    view_local: np.ndarray  # (n, 3) requested
    poses: tuple[GonioPose | None, ...]
    exact: np.ndarray  # (n,) bool
    reasons: tuple[str, ...]  # why a pair is not exact ("" where it is)

    @property
    def unreachable(self) -> np.ndarray:
        """Indices of the pairs the rig cannot reproduce exactly."""
        return np.flatnonzero(~self.exact)


def _lamp_direction(lamp) -> np.ndarray:
    return direction(90.0 - lamp.elevation_deg, lamp.azimuth_deg)


def forward_directions(pose: GonioPose, config: GonioConfig) -> tuple[np.ndarray, np.ndarray]:
    """Light and view directions in the sample frame produced by ``pose`` (forward kinematics)."""
    lamp = next(lamp for lamp in config.lamps if lamp.id == pose.lamp_id)
    to_sample = pose.rotation().inv()
    light = to_sample.apply(_lamp_direction(lamp))
    view = to_sample.apply(direction(90.0, pose.rail_deg))
    return light, view


def _frame(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Orthonormal frame (columns) from ``first`` and the part of ``second`` orthogonal to it."""
    ortho = second - np.dot(second, first) * first
    norm = np.linalg.norm(ortho)
    if norm < 1e-12:  # parallel: any perpendicular will do
        ortho = np.cross(first, [1.0, 0.0, 0.0] if abs(first[0]) < 0.9 else [0.0, 1.0, 0.0])
        norm = np.linalg.norm(ortho)
    ortho = ortho / norm
    return np.column_stack([first, ortho, np.cross(first, ortho)])


def _rail_candidates(config: GonioConfig, lamp, separation_deg: float) -> list[float]:
    """Rail angles at which the camera is ``separation_deg`` away from the lamp (as seen from the
    sample), within the rail's range."""
    low, high = config.rail.azimuth_range_deg
    candidates = []
    # Lamp in the rail plane: the camera sits at the lamp azimuth plus or minus the separation.
    if abs(lamp.elevation_deg) < 1e-9:
        for sign in (1.0, -1.0):
            rail = lamp.azimuth_deg + sign * separation_deg
            if low - 1e-9 <= rail <= high + 1e-9:
                candidates.append(float(np.clip(rail, low, high)))
        return candidates
    # Lamp above or below the plane: cos(separation) = cos(elevation) cos(rail - azimuth).
    cosine = np.cos(np.radians(separation_deg)) / np.cos(np.radians(lamp.elevation_deg))
    if abs(cosine) <= 1:
        offset = np.degrees(np.arccos(cosine))
        for sign in (1.0, -1.0):
            rail = lamp.azimuth_deg + sign * offset
            if low - 1e-9 <= rail <= high + 1e-9:
                candidates.append(float(np.clip(rail, low, high)))
    return candidates


def _pose_for(config: GonioConfig, lamp, rail_deg: float, light: np.ndarray, view: np.ndarray):
    world = _frame(_lamp_direction(lamp), direction(90.0, rail_deg))
    local = _frame(light, view)
    rotation = Rotation.from_matrix(world @ local.T)
    yaw, tilt, roll = rotation.as_euler("ZYZ", degrees=True)
    return GonioPose(lamp.id, rail_deg, float(yaw), float(tilt), float(roll))


def _within_robot(config: GonioConfig, pose: GonioPose) -> bool:
    low, high = config.robot.tilt_range_deg
    return low - 1e-6 <= pose.tilt_deg <= high + 1e-6


def _solve_exact(config: GonioConfig, light: np.ndarray, view: np.ndarray) -> GonioPose | None:
    separation = float(angle_between_deg(light, view))
    if separation < config.minimum_lamp_camera_separation_deg:
        return None
    for lamp in config.lamps:
        for rail in _rail_candidates(config, lamp, separation):
            pose = _pose_for(config, lamp, rail, light, view)
            if _within_robot(config, pose):
                return pose
    return None


def _nearest_reachable(
    config: GonioConfig, light: np.ndarray, view: np.ndarray
) -> GonioPose | None:
    """For a pair closer than the lamp-camera minimum (e.g. retro-reflection), spread light and
    view symmetrically about their bisector to the minimum separation, in the first of a fan of
    planes through the bisector that the rig can serve, and solve that pair."""
    half = np.radians(config.minimum_lamp_camera_separation_deg) / 2 + 1e-9
    bisector = (light + view) / np.linalg.norm(light + view)
    frame = _frame(bisector, view - light)
    for turn in np.radians(np.arange(0.0, 180.0, 15.0)):
        axis = np.cos(turn) * frame[:, 1] + np.sin(turn) * frame[:, 2]
        pose = _solve_exact(
            config,
            np.cos(half) * bisector - np.sin(half) * axis,
            np.cos(half) * bisector + np.sin(half) * axis,
        )
        if pose is not None:
            return pose
    return None


def solve_pairs(config: GonioConfig, light_local=None, view_local=None) -> GonioSolution:
    """Solve every pair (default: Sattler's 81 x 81); unreachable pairs are kept and reported.

    Pairs that cannot be reproduced exactly get the nearest configuration the rig can reach and a
    reason; they are never dropped.
    """
    if light_local is None or view_local is None:
        directions = sattler_directions()
        light_local = np.repeat(directions, len(directions), axis=0)
        view_local = np.tile(directions, (len(directions), 1))
    poses: list[GonioPose | None] = []
    exact: list[bool] = []
    reasons: list[str] = []
    for light, view in zip(light_local, view_local, strict=True):
        pose = _solve_exact(config, light, view)
        if pose is not None:
            poses.append(pose)
            exact.append(True)
            reasons.append("")
            continue
        separation = float(angle_between_deg(light, view))
        poses.append(_nearest_reachable(config, light, view))  # None: nothing close either
        exact.append(False)
        reasons.append(
            f"light and view {separation:.2f} deg apart, below the lamp-camera minimum of "
            f"{config.minimum_lamp_camera_separation_deg:g} deg"
            if separation < config.minimum_lamp_camera_separation_deg
            else "no lamp position serves this pair within the robot's tilt range"
        )
    return GonioSolution(
        np.asarray(light_local),
        np.asarray(view_local),
        tuple(poses),
        np.array(exact),
        tuple(reasons),
    )


def perturbed_pose(pose: GonioPose, config: GonioConfig, rng: np.random.Generator) -> GonioPose:
    """The pose the robot actually reaches: each orientation axis off by ``repeatability_deg``
    and the sample centre off by ``repeatability_mm`` per axis (1 sigma), so that frames of
    different pairs need registration."""
    robot = config.robot
    yaw, tilt, roll = np.array([pose.yaw_deg, pose.tilt_deg, pose.roll_deg]) + (
        robot.repeatability_deg * rng.standard_normal(3)
    )
    offset = np.asarray(pose.offset_m) + 1e-3 * robot.repeatability_mm * rng.standard_normal(3)
    return GonioPose(
        pose.lamp_id, pose.rail_deg, float(yaw), float(tilt), float(roll), tuple(offset.tolist())
    )
