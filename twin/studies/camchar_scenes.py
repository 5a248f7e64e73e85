"""Chart photographs for camera characterization, rendered under uncontrolled conditions
(thesis 9.4.2): a glossy coating lit by a spot (specular highlights), an occluder casting a soft
shadow from a large light, a slightly bent chart; daylight, halogen, HMI or fluorescent light;
any camera of ``twin.components.RGB_CAMERA_RESPONSES``.

The render's three channels are the camera's relative response, so the field means are the
device RGB that ``recon.camera_char.estimate_response`` expects (linear, dark-free).
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np
import trimesh

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, from_colour, resample
from twin.components.detectors import rgb_camera_response
from twin.components.lamps import FINE_GRID, HMILamp
from twin.materials.calibration_targets import colorchecker_chart, esser_chart
from twin.materials.geometry import box
from twin.materials.surfaces import SurfacePart
from twin.render.render import render_scene
from twin.render.scene import PinholeCamera
from twin.render.shapes import mitsuba_shape
from twin.render.spectra import irregular_spectrum
from twin.render.transforms import look_at, rotate, scale, translate

__all__ = ["CHARTS", "LIGHTS", "ChartPhoto", "ChartScenario", "render_chart_photo"]

CHARTS = {"colorchecker": (colorchecker_chart, 6), "esser": (esser_chart, 11)}
LIGHTS = {"daylight": "D65", "halogen": "A", "fluorescent": "FL11", "hmi": None}
_CHART_SIZE_M = 0.2


@dataclass(frozen=True)
class ChartScenario:
    """What the photograph looks like."""

    chart: str = "esser"
    light: str = "daylight"
    camera: str = "Nikon D70"
    glossy: bool = True
    spot: bool = True
    occluder: bool = False
    bend: float = 0.0  # z offset at the chart's left and right edges, in chart widths
    pixels: int = 256
    spp: int = 64

    def __post_init__(self) -> None:
        if self.chart not in CHARTS:
            raise InputError(f"chart: expected one of {sorted(CHARTS)}, got {self.chart!r}")
        if self.light not in LIGHTS:
            raise InputError(f"light: expected one of {sorted(LIGHTS)}, got {self.light!r}")
        if not 0 <= self.bend <= 0.2:
            raise InputError(f"bend: expected 0 to 0.2 chart widths, got {self.bend}")


@dataclass(frozen=True)
class ChartPhoto:
    """The rendered photograph and everything the characterization needs."""

    image: np.ndarray  # (H, W, 3) device RGB
    field_rgb: np.ndarray  # (J, 3) means around the field centres
    field_positions: np.ndarray  # (J, 2) in metres on the chart
    reflectances: np.ndarray  # (J, K) on DEFAULT_GRID
    illuminant: np.ndarray  # (K,) relative, on DEFAULT_GRID
    true_response: np.ndarray  # (K, 3) relative, on DEFAULT_GRID


def _light_spectrum(light: str) -> SampledSpectra:
    if LIGHTS[light] is None:
        return HMILamp().intensity(FINE_GRID)
    spectrum = from_colour(colour.SDS_ILLUMINANTS[LIGHTS[light]])
    return resample(spectrum, FINE_GRID, method="pchip", out_of_range="zero")


def _bent(parts: list[SurfacePart], bend: float) -> list[SurfacePart]:
    """Bend the chart into a parabolic cylinder: z += bend x width x (2 x / width)^2."""
    bent = []
    for part in parts:
        # Subdivide so that the flat card and fields follow the curve instead of their corners.
        vertices, faces = trimesh.remesh.subdivide_to_size(
            part.mesh.vertices, part.mesh.faces, 0.005
        )
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        x = mesh.vertices[:, 0] / (_CHART_SIZE_M / 2)
        mesh.vertices[:, 2] += bend * _CHART_SIZE_M * x**2
        bent.append(SurfacePart(part.name, mesh, part.reflectance, part.roughness, part.conductor))
    return bent


def render_chart_photo(scenario: ChartScenario, *, seed: int = 0) -> ChartPhoto:
    """Render the chart photograph of ``scenario`` and extract the field means."""
    make_chart, _ = CHARTS[scenario.chart]
    parts = make_chart(_CHART_SIZE_M)
    if scenario.glossy:
        parts = [parts[0]] + [
            SurfacePart(p.name, p.mesh, p.reflectance, roughness=0.15) for p in parts[1:]
        ]
    if scenario.bend:
        parts = _bent(parts, scenario.bend)
    camera = PinholeCamera(np.array([0.0, -0.05, 0.6]), 0.26, scenario.pixels, up=(0.0, 1.0, 0.0))
    response = rgb_camera_response(scenario.camera, FINE_GRID, out_of_range="zero")
    light = _light_spectrum(scenario.light)
    scene: dict[str, object] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": camera.mitsuba_sensor(response, scenario.spp),
    }
    if scenario.spot:
        scene["light"] = {
            "type": "spot",
            "to_world": look_at(origin=[0.0, 0.5, 0.7], target=[0, 0, 0], up=[0, 0, 1]),
            "intensity": irregular_spectrum(light * 2.0),
            "cutoff_angle": 20.0,
            "beam_width": 12.0,
        }
    else:
        scene["light"] = {
            "type": "rectangle",
            "to_world": translate([0.0, 0.3, 0.6]) @ rotate([1, 0, 0], 150.0) @ scale(0.3),
            "emitter": {"type": "area", "radiance": irregular_spectrum(light)},
        }
    if scenario.occluder:
        parts = parts + [
            SurfacePart(
                "occluder",
                box((0.06, 0.12, 0.12), (0.08, 0.02, 0.08)),
                SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.05)),
            )
        ]
    for part in parts:
        scene[part.name] = mitsuba_shape(part)
    image = render_scene(scene, seed)

    patches = [part for part in parts if part.name.startswith("patch_")]
    centres = np.array([part.mesh.centroid for part in patches])
    centres[:, 2] = [part.mesh.vertices[:, 2].max() for part in patches]  # the field's top
    pixels = camera.project(centres)
    field_rgb = np.array(
        [
            image[int(row) - 1 : int(row) + 2, int(column) - 1 : int(column) + 2]
            .reshape(-1, 3)
            .mean(axis=0)
            for column, row in pixels
        ]
    )
    reflectances = np.array(
        [resample(part.reflectance, DEFAULT_GRID, method="box").values for part in patches]
    )
    return ChartPhoto(
        image=image,
        field_rgb=field_rgb,
        field_positions=centres[:, :2],
        reflectances=np.clip(reflectances, 0, 1),
        illuminant=resample(light, DEFAULT_GRID, method="box").values,
        true_response=rgb_camera_response(scenario.camera, DEFAULT_GRID).values.T,
    )
