"""Geometric calibration of the dome's cameras from checkerboard frames: intrinsics, extrinsics.

The thesis leaves the geometric calibration of its dome out of scope (10.3). Here it runs
through OpenCV on the ``geometric`` frames of a dome calibration capture (a
checkerboard flat on the holder and on a wedge at several stage positions, every LED on):

1. the board's inner corners in every frame (:func:`board_corners`:
   ``cv2.findChessboardCorners``, refined by ``cv2.cornerSubPix``; the sector-based
   ``cv2.findChessboardCornersSB`` where it fails);
2. the board's pose on its wedge and the stage angle of every frame are known, so the corners
   of all frames are points of one rigid, non-planar calibration object in the world frame
   (Tsai's setting rather than Zhang's): ``cv2.calibrateCamera`` fits the focal length and the
   world pose to all of them at once, then ``cv2.solvePnP`` polishes the pose. The principal
   point stays at the window's centre and the lens distortion at the camera's nominal
   coefficients: through a 15 degree field of view a 4 cm board moves the principal point
   along with the camera's orientation (fitted freely, it lands tens of pixels off), and five
   views of it do not constrain the distortion. The focal length trades against the camera's
   distance in so narrow a view (the board's depth varies by 1 % of it); it is kept only where
   its standard deviation (:func:`focal_length_uncertainty`) is below
   :data:`FOCAL_LENGTH_TOLERANCE`, else the nominal one stays and the pose is fitted.

OpenCV lists the board's corners from any of its ends (its 180 degree symmetry, and rows or
columns in reverse); the nominal camera (the rig's design) picks the listing whose projection
lies nearest.

Conventions: OpenCV's camera model (x right, y down, z forward; pixel centres at integer
coordinates); the world frame of :mod:`hwbridge.dome_layout` (origin at the sample centre on the
stage, z up); the sample frame is the world turned about z by the stage angle.

References
----------
- Tsai, R. (1987). A versatile camera calibration technique for high-accuracy 3D machine
  vision metrology using off-the-shelf TV cameras and lenses. IEEE Journal on Robotics and
  Automation 3(4), 323-344. doi:10.1109/JRA.1987.1087109
- Zhang, Z. (2000). A flexible new technique for camera calibration. IEEE TPAMI 22(11),
  1330-1334. doi:10.1109/34.888718
- The thesis, section 10.3 (geometric calibration out of its scope).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from hwbridge.schema import DomeCamera
from recon.errors import InputError

__all__ = [
    "CameraGeometry",
    "GeometricCalibration",
    "board_corners",
    "calibrate_camera_geometry",
    "focal_length_uncertainty",
    "stage_rotation",
]

_SUBPIXEL_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)
FOCAL_LENGTH_TOLERANCE = 0.01
"""Largest relative standard deviation at which a fitted focal length replaces the nominal one."""

_FOCAL_LENGTH_ONLY = (
    cv2.CALIB_USE_INTRINSIC_GUESS
    | cv2.CALIB_FIX_PRINCIPAL_POINT
    | cv2.CALIB_FIX_ASPECT_RATIO
    | cv2.CALIB_ZERO_TANGENT_DIST
    | cv2.CALIB_FIX_K1
    | cv2.CALIB_FIX_K2
    | cv2.CALIB_FIX_K3
)


def stage_rotation(stage_deg: float) -> np.ndarray:
    """``(3, 3)`` sample-to-world rotation of the rotation stage at ``stage_deg`` (about z).

    Examples
    --------
    >>> np.round(stage_rotation(90.0) @ [1.0, 0.0, 0.0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    turn = np.radians(float(stage_deg))
    cos, sin = np.cos(turn), np.sin(turn)
    return np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class CameraGeometry:
    """A calibrated (or nominal) camera in OpenCV's model and the dome's world frame.

    Attributes
    ----------
    camera_matrix
        ``(3, 3)`` intrinsics of the stored window.
    distortion
        ``(5,)`` OpenCV's distortion coefficients.
    rotation_world_to_camera
        ``(3, 3)``.
    position_m
        ``(3,)`` the projection centre in the world frame.
    """

    camera_matrix: np.ndarray
    distortion: np.ndarray
    rotation_world_to_camera: np.ndarray
    position_m: np.ndarray

    @classmethod
    def nominal(cls, camera: DomeCamera) -> CameraGeometry:
        """The nominal camera a dome store records (its geometry's ``cameras``)."""
        return cls(
            np.asarray(camera.camera_matrix, np.float64),
            np.asarray(camera.distortion, np.float64),
            np.asarray(camera.rotation_world_to_camera, np.float64),
            np.asarray(camera.position_m, np.float64),
        )

    @classmethod
    def from_json(cls, entry: Mapping[str, object]) -> CameraGeometry:
        """From :meth:`to_json` (a calibration file's summary)."""
        try:
            return cls(
                np.asarray(entry["camera_matrix"], np.float64).reshape(3, 3),
                np.asarray(entry["distortion"], np.float64).reshape(5),
                np.asarray(entry["rotation_world_to_camera"], np.float64).reshape(3, 3),
                np.asarray(entry["position_m"], np.float64).reshape(3),
            )
        except (KeyError, TypeError, ValueError) as error:
            raise InputError(
                f"camera geometry: expected camera_matrix (3x3), distortion (5), "
                f"rotation_world_to_camera (3x3) and position_m (3), got {error}"
            ) from None

    def to_json(self) -> dict[str, list[Any]]:
        return {
            "camera_matrix": self.camera_matrix.tolist(),
            "distortion": self.distortion.tolist(),
            "rotation_world_to_camera": self.rotation_world_to_camera.tolist(),
            "position_m": self.position_m.tolist(),
        }

    def pose_vectors(self) -> tuple[np.ndarray, np.ndarray]:
        """OpenCV's ``rvec`` (Rodrigues) and ``tvec`` of the world-to-camera transform."""
        rotation = self.rotation_world_to_camera
        return cv2.Rodrigues(rotation)[0], -rotation @ self.position_m

    def project(self, points_world: np.ndarray) -> np.ndarray:
        """Image points ``(n, 2)`` (pixel centres at integers) of world points ``(n, 3)``."""
        rvec, tvec = self.pose_vectors()
        points = np.asarray(points_world, np.float64).reshape(-1, 1, 3)
        image, _ = cv2.projectPoints(points, rvec, tvec, self.camera_matrix, self.distortion)
        return image.reshape(-1, 2)

    def position_in_sample(self, stage_deg: float) -> np.ndarray:
        """The projection centre in the sample frame at stage angle ``stage_deg``."""
        return stage_rotation(stage_deg).T @ self.position_m

    def deviation_from(self, other: CameraGeometry) -> dict[str, float]:
        """How far this camera lies from ``other`` (e.g. the nominal one): focal length in %,
        principal point in px, position in mm, orientation in degrees."""
        relative = self.rotation_world_to_camera @ other.rotation_world_to_camera.T
        angle = np.degrees(np.arccos(np.clip((np.trace(relative) - 1) / 2, -1.0, 1.0)))
        return {
            "focal_length_pct": float(
                100 * (self.camera_matrix[0, 0] / other.camera_matrix[0, 0] - 1)
            ),
            "principal_point_px": float(
                np.linalg.norm(self.camera_matrix[:2, 2] - other.camera_matrix[:2, 2])
            ),
            "position_mm": float(1000 * np.linalg.norm(self.position_m - other.position_m)),
            "rotation_deg": float(angle),
        }


def _grey(values: np.ndarray) -> np.ndarray | None:
    """8-bit grey of a linear frame, its 0.5th to 99.5th percentile stretched."""
    top, low = float(np.percentile(values, 99.5)), float(np.percentile(values, 0.5))
    if not top > low:
        return None
    return np.clip(255 * (values - low) / (top - low), 0, 255).astype(np.uint8)


def board_corners(image: np.ndarray, inner_corners: tuple[int, int]) -> np.ndarray | None:
    """The inner corners ``(columns x rows, 2)`` of a checkerboard in a linear grey frame, in
    OpenCV's order and pixel convention; ``None`` where the board is not found (seen too
    obliquely).

    ``cv2.findChessboardCorners`` refined by ``cv2.cornerSubPix``; where it fails (noisy frames
    of the spectral camera, steep views) ``cv2.findChessboardCornersSB`` on the frame enlarged
    twice (its sector test needs a few pixels per square)."""
    grey = _grey(np.asarray(image, np.float64))
    if grey is None:
        return None
    pattern = tuple(int(n) for n in inner_corners)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(grey, pattern, flags=flags)
    if found:
        spacing = np.median(np.linalg.norm(np.diff(corners.reshape(-1, 2), axis=0), axis=1))
        window = int(max(2, spacing // 3))
        refined = cv2.cornerSubPix(grey, corners, (window, window), (-1, -1), _SUBPIXEL_CRITERIA)
        return refined.reshape(-1, 2).astype(np.float64)
    larger = cv2.resize(grey, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC)
    flags = cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    found, corners = cv2.findChessboardCornersSB(larger, pattern, flags=flags)
    if not found:
        return None
    return (corners.reshape(-1, 2).astype(np.float64) + 0.5) / 2 - 0.5


@dataclass(frozen=True)
class GeometricCalibration:
    """One camera calibrated from checkerboard frames.

    Attributes
    ----------
    geometry
        The calibrated camera.
    frames_used, frames_total
        Frames in which the board was found, of those given.
    reprojection_rms_px
        RMS distance of the found corners from their projections by ``geometry`` (``None``
        where no frame showed the board).
    fitted
        What the frames determined: ``"focal length and pose"``, ``"pose"`` (the nominal
        intrinsics kept: one plane orientation, or a focal length less certain than
        :data:`FOCAL_LENGTH_TOLERANCE`) or ``"nothing"`` (the nominal camera kept).
    """

    geometry: CameraGeometry
    frames_used: int
    frames_total: int
    reprojection_rms_px: float | None
    fitted: str


def focal_length_uncertainty(
    world_m: np.ndarray,
    image_xy: np.ndarray,
    camera_matrix: np.ndarray,
    distortion: np.ndarray,
    rvec: np.ndarray,
    tvec: np.ndarray,
) -> float:
    """Relative standard deviation of the focal length fitted with the pose to the points
    ``(n, 3)`` -> ``(n, 2)``: :math:`\\sigma^2 (J^T J)^{-1}` of the seven parameters (rotation,
    translation, one focal length), :math:`\\sigma^2` the residuals' variance per coordinate
    (Gauss-Newton's covariance, from ``cv2.projectPoints``' Jacobian)."""
    points = np.asarray(world_m, np.float64).reshape(-1, 1, 3)
    projected, jacobian = cv2.projectPoints(points, rvec, tvec, camera_matrix, distortion)
    columns = np.column_stack([jacobian[:, :6], jacobian[:, 6] + jacobian[:, 7]])
    residual = projected.reshape(-1) - np.asarray(image_xy, np.float64).reshape(-1)
    variance = residual @ residual / max(residual.size - columns.shape[1], 1)
    covariance = variance * np.linalg.pinv(columns.T @ columns)
    return float(np.sqrt(covariance[6, 6]) / camera_matrix[0, 0])


def _listing(found: np.ndarray, expected: np.ndarray, inner_corners: tuple[int, int]) -> np.ndarray:
    """``found`` reordered to the board's listing: as OpenCV listed them, from the opposite
    end (the board turned by 180 degrees), or with its rows or columns in reverse, whichever
    lies nearest to the expected image points."""
    grid = found.reshape(inner_corners[1], inner_corners[0], 2)
    candidates = [grid, grid[::-1, ::-1], grid[::-1], grid[:, ::-1]]
    distances = [np.linalg.norm(c.reshape(-1, 2) - expected, axis=1).mean() for c in candidates]
    return candidates[int(np.argmin(distances))].reshape(-1, 2)


def calibrate_camera_geometry(
    images: Sequence[np.ndarray],
    board_to_world: Sequence[np.ndarray],
    board_points_m: np.ndarray,
    inner_corners: tuple[int, int],
    nominal: CameraGeometry,
) -> GeometricCalibration:
    """Intrinsics and world pose of one camera from its checkerboard frames (module docstring).

    Parameters
    ----------
    images
        Linear grey frames ``(H, W)`` of the board, one per pose.
    board_to_world
        ``(4, 4)`` pose of the board in the world frame for each frame (its pose on the wedge
        in the sample frame, turned by the stage).
    board_points_m
        ``(columns x rows, 3)`` the inner corners in the board's frame (z = 0), in OpenCV's
        order.
    inner_corners
        ``(columns, rows)`` of inner corners.
    nominal
        The camera as designed: the start of the fit, the judge of the board's listing, and
        what is kept of it that the frames do not determine (its principal point and lens
        distortion; its focal length too with one plane orientation; everything without a
        board found).

    Returns
    -------
    GeometricCalibration
    """
    points = np.asarray(board_points_m, np.float64)
    if len(images) != len(board_to_world) or points.shape != (np.prod(inner_corners), 3):
        raise InputError(
            f"images, board_to_world, board_points_m: expected one pose per image and "
            f"{np.prod(inner_corners)} board points, got {len(images)}, {len(board_to_world)} "
            f"and {points.shape}"
        )
    world_points, image_points = [], []
    for image, pose in zip(images, board_to_world, strict=True):
        found = board_corners(image, inner_corners)
        if found is None:
            continue
        world = points @ np.asarray(pose)[:3, :3].T + np.asarray(pose)[:3, 3]
        world_points.append(world)
        image_points.append(_listing(found, nominal.project(world), inner_corners))
    if not image_points:
        return GeometricCalibration(nominal, 0, len(images), None, "nothing")
    every_world, every_image = np.concatenate(world_points), np.concatenate(image_points)
    matrix, distortion = nominal.camera_matrix.copy(), nominal.distortion.copy()
    rvec, tvec = nominal.pose_vectors()
    fitted = "pose"
    if len(image_points) >= 2:
        height, width = np.shape(images[0])
        _, focal_matrix, _, rvecs, tvecs = cv2.calibrateCamera(
            [every_world.astype(np.float32)],
            [every_image.astype(np.float32)],
            (width, height),
            matrix.copy(),
            distortion.copy(),
            flags=_FOCAL_LENGTH_ONLY,
        )
        uncertainty = focal_length_uncertainty(
            every_world, every_image, focal_matrix, distortion, rvecs[0], tvecs[0]
        )
        if uncertainty <= FOCAL_LENGTH_TOLERANCE:
            matrix, rvec, tvec, fitted = focal_matrix, rvecs[0], tvecs[0], "focal length and pose"
    _, rvec, tvec = cv2.solvePnP(
        every_world, every_image, matrix, distortion, rvec, tvec, useExtrinsicGuess=True
    )
    rotation = cv2.Rodrigues(rvec)[0]
    geometry = CameraGeometry(
        matrix, distortion.reshape(5), rotation, (-rotation.T @ tvec).reshape(3)
    )
    residual = np.linalg.norm(geometry.project(every_world) - every_image, axis=1)
    return GeometricCalibration(
        geometry,
        len(image_points),
        len(images),
        float(np.sqrt(np.mean(residual**2))),
        fitted,
    )
