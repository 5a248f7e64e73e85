"""The camera of a user's photograph of the sample, recovered from the sample's four corners
(``spectwin validate --photo``, thesis 4.2).

The sample is a square of side ``size_m`` in the plane z = 0 of the world, centred at the
origin, facing +z: the plane the BTF's textures are rectified to
(:mod:`twin.render.plugins.btf_bsdf`: texel row 0 at the +y edge, column 0 at the -x edge). Its
corners, as the photograph shows them, are given in the order of the BTF's texture: top left
(-x, +y), top right (+x, +y), bottom right (+x, -y), bottom left (-x, -y). With the focal length
in pixels and the principal point at the image centre, the camera's pose follows from the four
corners by OpenCV's ``solvePnP`` (IPPE for a square, Collins and Bartoli 2014); the corners'
reprojection error says how well a square of that focal length explains them.

An environment map's directions are those of this world frame (:mod:`twin.validate.
preview_lighting`): a lat-long map of the light at the sample, +z its normal.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.render.spectra import ldsampler, specfilm
from twin.render.transforms import matrix
from twin.validate.preview_geometry import SurfaceView

__all__ = ["PhotoCamera", "fov_deg", "recover_camera", "square_corners"]


def square_corners(size_m: float) -> np.ndarray:
    """``(4, 3)`` the sample square's corners in the order of the BTF's texture (module
    docstring), metres."""
    half = size_m / 2
    return np.array(
        [[-half, half, 0.0], [half, half, 0.0], [half, -half, 0.0], [-half, -half, 0.0]]
    )


def fov_deg(focal_px: float, width: int) -> float:
    """Horizontal field of view (degrees) of a pinhole camera ``width`` pixels wide."""
    return float(np.degrees(2 * np.arctan(width / 2 / focal_px)))


@dataclass(frozen=True)
class PhotoCamera:
    """A pinhole camera of a photograph: ``width x height`` pixels, focal length ``focal_px``,
    principal point at the centre, pose ``rotation`` (world to camera, OpenCV axes: x right,
    y down, z forward) and ``translation`` (m), as :func:`cv2.solvePnP` gives them."""

    width: int
    height: int
    focal_px: float
    rotation: np.ndarray
    translation: np.ndarray

    @property
    def position_m(self) -> np.ndarray:
        """The camera's centre in the world (m)."""
        return -self.rotation.T @ self.translation

    def project(self, points_m: np.ndarray) -> np.ndarray:
        """Continuous pixel coordinates ``(n, 2)`` (column, row; pixel centres at +0.5) of
        world points."""
        camera = np.atleast_2d(points_m) @ self.rotation.T + self.translation
        centre = np.array([self.width / 2, self.height / 2])
        return centre + self.focal_px * camera[:, :2] / camera[:, 2:3]

    def ray(self, column: float, row: float) -> np.ndarray:
        """The unit ray through the image point ``(column, row)`` in the camera's axes."""
        ray = np.array([column - self.width / 2, row - self.height / 2, self.focal_px])
        return ray / np.linalg.norm(ray)

    def sample_surface(self, mask: np.ndarray) -> SurfaceView:
        """The sample's plane z = 0 at the pixels of ``mask`` ``(height, width)``: their
        points, normals (+z) and unit directions towards the camera."""
        rows, columns = np.nonzero(mask)
        rays = np.array([self.ray(c + 0.5, r + 0.5) for r, c in zip(rows, columns, strict=True)])
        world = rays.reshape(-1, 3) @ self.rotation  # camera axes to the world's
        origin = self.position_m
        points = origin - (origin[2] / world[:, 2])[:, None] * world
        normals = np.broadcast_to(np.array([0.0, 0.0, 1.0]), points.shape)
        return SurfaceView(mask, points, normals, -world)

    def mitsuba_sensor(self, channels: SampledSpectra, spp: int) -> dict[str, object]:
        """A Mitsuba ``perspective`` sensor of this camera with ``specfilm`` ``channels``
        (:func:`twin.render.light_groups.render_lit` takes it)."""
        # Mitsuba's camera frame: +x left, +y up, +z forward; OpenCV's: x right, y down.
        to_world = np.eye(4)
        to_world[:3, :3] = self.rotation.T @ np.diag([-1.0, -1.0, 1.0])
        to_world[:3, 3] = self.position_m
        return {
            "type": "perspective",
            "fov": fov_deg(self.focal_px, self.width),
            "fov_axis": "x",
            "to_world": matrix(to_world.tolist()),
            "film": specfilm(channels, self.width, self.height),
            "sampler": ldsampler(spp),
        }


def recover_camera(
    corners_px: np.ndarray, size_m: float, width: int, height: int, focal_px: float
) -> tuple[PhotoCamera, float]:
    """The camera that sees the sample square's corners at ``corners_px`` (module docstring).

    Parameters
    ----------
    corners_px
        ``(4, 2)`` column, row of the corners in the texture's order (pixel centres at +0.5).
    size_m
        The sample's side (m): it sets the distance, not the image.
    width, height
        The photograph's size in pixels.
    focal_px
        Focal length in pixels.

    Returns
    -------
    tuple of PhotoCamera and float
        The camera, and the corners' largest reprojection error (pixels).

    Raises
    ------
    InputError
        If the corners do not make a quadrilateral seen from the sample's front.
    """
    corners = np.asarray(corners_px, np.float64).reshape(4, 2)
    intrinsics = np.array([[focal_px, 0, width / 2], [0, focal_px, height / 2], [0, 0, 1]])
    found, rotation_vector, translation = cv2.solvePnP(
        square_corners(size_m),
        corners,
        intrinsics,
        None,
        flags=cv2.SOLVEPNP_IPPE_SQUARE,
    )
    if not found:
        raise InputError(
            "--sample-corners: no camera pose sees a square at these corners; expected the "
            "corners in the texture's order (top left, top right, bottom right, bottom left)"
        )
    rotation = cv2.Rodrigues(rotation_vector)[0]
    camera = PhotoCamera(width, height, float(focal_px), rotation, translation.ravel())
    if camera.position_m[2] <= 0:
        raise InputError(
            "--sample-corners: they show the sample from behind; expected the corners in the "
            "texture's order, clockwise as the photograph shows them"
        )
    error = float(np.abs(camera.project(square_corners(size_m)) - corners).max())
    return camera, error
