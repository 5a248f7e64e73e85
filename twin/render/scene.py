"""Mitsuba scenes of the rigs: a material on its holder, posed by the rig, lit by one lamp or LED,
seen by one camera whose ``specfilm`` channels are the sensor's electron responses.

Channel responses are ``Sensor.electron_responses`` (optics etendue x QE x filter x
:math:`\\lambda / hc`), so a render is directly the mean photo-electron rate per pixel (e-/s) for
the given lamp spectrum: ``render -> x exposure -> Sensor.capture -> raw frame``. Renders are made
at a chosen resolution; each rendered pixel stands for one sensor pixel of the camera at that
place of the image (a sub-sampled sensor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.materials.surfaces import SurfacePart, transformed
from twin.render.light_groups import lamp_weighted_channels
from twin.render.render import render_scene
from twin.render.shapes import mitsuba_shape
from twin.render.spectra import irregular_spectrum, ldsampler, specfilm
from twin.render.variant import activate
from twin.rigs.hemisphere import direction

__all__ = ["PinholeCamera", "centred_window_offset", "lamp_position", "render_view"]


def centred_window_offset(pixels, window):
    """Pixels between the sensor's edge and a centred read-out ``window`` of ``pixels`` (numbers
    or integer arrays)."""
    return (pixels - window) // 2


@dataclass(frozen=True)
class PinholeCamera:
    """A camera looking at the rig centre from ``position_m``; square image of ``pixels``.

    ``field_of_view_m`` is the width of the field at the rig centre. With ``window`` only the
    centred ``window x window`` pixels are read out (a sensor region of interest): images and
    projected coordinates are those of the window.
    """

    position_m: np.ndarray
    field_of_view_m: float
    pixels: int
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    window: int | None = None

    @property
    def window_offset(self) -> int:
        """Pixels between the sensor's edge and the window's."""
        return 0 if self.window is None else centred_window_offset(self.pixels, self.window)

    @property
    def fov_deg(self) -> float:
        distance = float(np.linalg.norm(self.position_m))
        return float(2 * np.degrees(np.arctan(self.field_of_view_m / 2 / distance)))

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors (left, up, forward) of the camera in the world."""
        forward = -np.asarray(self.position_m, np.float64)
        forward /= np.linalg.norm(forward)
        up = np.asarray(self.up, np.float64)
        if abs(np.dot(up, forward)) > 0.999:
            up = np.array([0.0, 1.0, 0.0])
        left = np.cross(up, forward)
        left /= np.linalg.norm(left)
        return left, np.cross(forward, left), forward

    def project(self, points_m: np.ndarray) -> np.ndarray:
        """Continuous pixel coordinates ``(n, 2)`` (column, row; pixel centres at +0.5)."""
        left, up, forward = self.frame()
        relative = np.atleast_2d(points_m) - self.position_m
        depth = relative @ forward
        focal = self.pixels / 2 / np.tan(np.radians(self.fov_deg) / 2)
        column = self.pixels / 2 - focal * (relative @ left) / depth
        row = self.pixels / 2 - focal * (relative @ up) / depth
        return np.column_stack([column, row]) - self.window_offset

    def mitsuba_sensor(self, channels: SampledSpectra, spp: int) -> dict[str, object]:
        activate()
        import mitsuba as mi

        left, up, forward = self.frame()
        film = specfilm(channels, self.pixels, self.pixels)
        if self.window is not None:
            if not 0 < self.window <= self.pixels:
                raise InputError(f"window: expected 1 to {self.pixels} pixels, got {self.window}")
            film |= {
                "crop_offset_x": self.window_offset,
                "crop_offset_y": self.window_offset,
                "crop_width": self.window,
                "crop_height": self.window,
            }
        return {
            "type": "perspective",
            "fov": self.fov_deg,
            "to_world": mi.ScalarTransform4f.look_at(
                origin=self.position_m.tolist(), target=[0.0, 0.0, 0.0], up=up.tolist()
            ),
            "film": film,
            "sampler": ldsampler(spp),
        }


def render_view(
    parts: list[SurfacePart],
    sample_to_world: np.ndarray,
    camera: PinholeCamera,
    channels: SampledSpectra,
    light_position_m: np.ndarray,
    light_intensity: SampledSpectra,
    *,
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """Render ``parts`` moved by the 4x4 ``sample_to_world``, lit by a point light of spectral
    intensity ``light_intensity`` (W sr^-1 nm^-1, on the channels' grid); returns ``(H, W, n)``.

    The lamp spectrum is moved into the film's channel responses and the point light emits a
    flat unit spectrum (:mod:`twin.render.light_groups`): the expectation is unchanged, and the
    per-band
    noise of spiky lamp spectra (the HMI's emission lines: 49 % per pixel and band at 64 spp
    before, see ``tests/twin``) falls to the level of smooth ones; unit-area channels give weak
    bands their share of wavelength samples (the K4's blue bands under the HMI lamp: 30 % noise
    at 400 nm, 64 spp, before).
    """
    normalized, areas = lamp_weighted_channels(channels, light_intensity)
    flat = SampledSpectra(channels.grid, np.ones(channels.grid.size))
    scene: dict[str, object] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": camera.mitsuba_sensor(normalized, spp),
        "light": {
            "type": "point",
            "position": np.asarray(light_position_m, np.float64).tolist(),
            "intensity": irregular_spectrum(flat),
        },
    }
    for part in parts:
        scene[part.name] = mitsuba_shape(transformed(part, sample_to_world))
    return render_scene(scene, seed) * areas


def lamp_position(azimuth_deg: float, elevation_deg: float, distance_m: float) -> np.ndarray:
    """Position of a lamp at ``distance_m`` from the rig centre."""
    return distance_m * direction(90.0 - elevation_deg, azimuth_deg)
