"""Builders of the four ground-truth materials (colour checker, red fabric, Lego,
wallpaper). Each returns surface parts in the sample frame: z is the normal, the sample fills
``[-size/2, size/2]^2`` around the origin and rests on z = 0.

Their spectral reflectances are designed on a 5 nm grid (``MATERIAL_GRID``). Colours come from
the ColorChecker (``colour``); metamers are designed for the dome's RGB camera under the dome's
white LEDs (``recon.metamers``). Renders use the same spectra on ``FINE_GRID``.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import trimesh

from recon.metamers import design_metamer
from recon.spectra import SampledSpectra, resample
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.components.targets import colorchecker_reflectances
from twin.materials.config import (
    ColorChecker16Config,
    FabricConfig,
    LegoConfig,
    WallpaperConfig,
)
from twin.materials.geometry import box, height_field, tube
from twin.materials.surfaces import MATERIAL_GRID, SurfacePart
from twin.rigs.camera_config import load_camera_config

__all__ = [
    "MATERIAL_GRID",
    "build_colorchecker16",
    "build_fabric",
    "build_lego",
    "build_wallpaper",
    "chart_colour",
    "dome_camera_and_light",
    "metamer_of",
    "on_fine_grid",
]


@cache
def _chart_reflectances() -> SampledSpectra:
    """The ColorChecker's 24 patches on ``MATERIAL_GRID``, resampled once per process (a chart
    takes 17 of them)."""
    return colorchecker_reflectances(MATERIAL_GRID)


def chart_colour(name: str, scale: float = 1.0) -> SampledSpectra:
    """A ColorChecker patch reflectance (``ColorChecker N Ohta``), optionally scaled."""
    return _chart_reflectances().row(name) * scale


def dome_camera_and_light() -> tuple[SampledSpectra, SampledSpectra]:
    """The dome RGB camera's quantum efficiency (R, G, B) and the dome LED spectrum."""
    response = load_camera_config("svs_vistek_4022").quantum_efficiency.curve(MATERIAL_GRID)
    return response, PhosphorWhiteLED().intensity(MATERIAL_GRID)


def metamer_of(reflectance: SampledSpectra, seed: int, percent: float = 20.0) -> SampledSpectra:
    """A smooth metamer of ``reflectance`` for the dome camera under the dome LEDs."""
    response, light = dome_camera_and_light()
    return design_metamer(
        reflectance,
        response,
        light,
        np.random.default_rng(seed),
        relative_difference_percent=percent,
    )


def on_fine_grid(reflectance: SampledSpectra) -> SampledSpectra:
    """The design spectrum on the render grid (linear in between, held constant outside)."""
    return resample(reflectance, FINE_GRID, out_of_range="clamp")


_THICKNESS_M = 0.001


def build_colorchecker16(config: ColorChecker16Config):
    """4 x 4 chart fields on a black card; some fields carry a glossy coating."""
    pitch = config.size_m / 4
    parts, spectra = [], {}
    black = chart_colour("black 2 (1.5 D)")
    parts.append(
        SurfacePart(
            "card",
            box((0, 0, _THICKNESS_M / 2), (config.size_m, config.size_m, _THICKNESS_M)),
            on_fine_grid(black),
        )
    )
    for index, name in enumerate(config.fields):
        row, column = divmod(index, 4)
        centre = (
            -config.size_m / 2 + (column + 0.5) * pitch,
            config.size_m / 2 - (row + 0.5) * pitch,
        )
        reflectance = chart_colour(name)
        part_name = f"field_{index:02d}"
        spectra[part_name] = reflectance
        parts.append(
            SurfacePart(
                part_name,
                box((*centre, 1.5 * _THICKNESS_M), (0.85 * pitch, 0.85 * pitch, _THICKNESS_M)),
                on_fine_grid(reflectance),
                roughness=config.gloss_roughness if name in config.glossy_fields else None,
            )
        )
    return parts, spectra, ()


def _thread_path(
    along: np.ndarray, across: float, pitch: float, phase: float, amplitude: float, axis: int
) -> np.ndarray:
    """Centre line of a thread: over one crossing thread, under the next (period two pitches)."""
    lift = 2 * amplitude + amplitude * np.cos(np.pi * along / pitch + phase)
    fixed = np.full_like(along, across)
    return np.column_stack([along, fixed, lift] if axis == 0 else [fixed, along, lift])


def build_fabric(config: FabricConfig):
    """Plain weave: warp threads along x (dark and light red, metameric for the dome camera),
    weft threads along y (grey and metallic silver)."""
    dark_red = chart_colour("red", 0.8)
    spectra = {
        "dark_red": dark_red,
        "light_red": metamer_of(dark_red, config.seed),
        "grey": chart_colour("neutral 5 (.70 D)"),
    }
    count, half = config.threads_per_direction, config.size_m / 2
    pitch = config.size_m / count
    along = np.linspace(-half, half, 8 * count + 1)
    amplitude = 0.9 * config.thread_radius_m
    threads: dict[str, list[trimesh.Trimesh]] = {name: [] for name in (*spectra, "silver")}
    for index in range(count):
        across = -half + (index + 0.5) * pitch
        warp = "dark_red" if index % 2 == 0 else "light_red"
        weft = "grey" if index % 2 == 0 else "silver"
        threads[warp].append(
            tube(
                _thread_path(along, across, pitch, np.pi * index, amplitude, 0),
                config.thread_radius_m,
            )
        )
        threads[weft].append(
            tube(
                _thread_path(along, across, pitch, np.pi * (index + 1), amplitude, 1),
                config.thread_radius_m,
            )
        )
    black = on_fine_grid(chart_colour("black 2 (1.5 D)"))
    parts = [
        SurfacePart(
            "backing",
            box((0, 0, -_THICKNESS_M / 2), (config.size_m, config.size_m, _THICKNESS_M)),
            black,
        )
    ]
    for name, meshes in threads.items():
        # trimesh types the result as any Geometry (or a list); for meshes it is one Trimesh
        mesh: trimesh.Trimesh = trimesh.util.concatenate(meshes)  # type: ignore[assignment]
        if name == "silver":
            parts.append(
                SurfacePart(
                    name, mesh, on_fine_grid(spectra["grey"]), roughness=0.2, conductor="Ag"
                )
            )
        else:
            parts.append(SurfacePart(name, mesh, on_fine_grid(spectra[name])))
    return parts, spectra, (("dark_red", "light_red"),)


def build_lego(config: LegoConfig):
    """2 x 2 bricks of 2 x 2 studs (15.8 mm pitch, 9.6 mm high, studs 4.8 mm x 1.7 mm), glossy
    ABS; the last brick is a metamer of the one before it for the dome camera."""
    spectra = {f"brick_{i}": chart_colour(name) for i, name in enumerate(config.colours)}
    last = f"brick_{len(config.colours)}"
    spectra[last] = metamer_of(spectra[f"brick_{len(config.colours) - 1}"], config.seed)
    brick, height = 0.0158, 0.0096
    parts = []
    for index, (name, reflectance) in enumerate(spectra.items()):
        row, column = divmod(index, 2)
        centre = np.array([(column - 0.5) * brick, (0.5 - row) * brick])
        meshes = [box((*centre, height / 2), (brick - 0.0002, brick - 0.0002, height))]
        for dx in (-0.25, 0.25):
            for dy in (-0.25, 0.25):
                stud = trimesh.creation.cylinder(radius=0.0024, height=0.0017, sections=24)
                stud.apply_translation((*(centre + brick * np.array([dx, dy])), height + 0.00085))
                meshes.append(stud)
        parts.append(
            SurfacePart(
                name,
                # trimesh types the result as any Geometry (or a list); for meshes it is one Trimesh
                trimesh.util.concatenate(meshes),  # type: ignore[arg-type]
                on_fine_grid(reflectance),
                roughness=config.roughness,
            )
        )
    pair = (f"brick_{len(config.colours) - 1}", last)
    return parts, spectra, (pair,)


def build_wallpaper(config: WallpaperConfig):
    """Embossed paper: a height field of crossed cosines (damask-like ornament), glossy; raised
    areas printed in a second colour."""
    count = config.resolution
    coordinates = np.linspace(-config.size_m / 2, config.size_m / 2, count)
    x, y = np.meshgrid(coordinates, coordinates, indexing="xy")
    frequency = 2 * np.pi / config.pattern_period_m
    ornament = 0.5 + 0.25 * (np.cos(frequency * x) + np.cos(frequency * y)) * np.cos(
        frequency * (x + y) / 2
    )
    mesh = height_field(config.emboss_height_m * ornament, config.size_m)
    raised = mesh.triangles_center[:, 2] > 0.5 * config.emboss_height_m
    spectra = {
        "paper": chart_colour(config.paper_colour),
        "print": chart_colour(config.print_colour),
    }
    parts = [
        SurfacePart(
            name,
            # trimesh types the result as any Geometry (or a list); for meshes it is one Trimesh
            mesh.submesh([np.flatnonzero(mask)], append=True),  # type: ignore[arg-type]
            on_fine_grid(spectra[name]),
            roughness=config.roughness,
        )
        for name, mask in (("paper", ~raised), ("print", raised))
    ]
    return parts, spectra, ()
