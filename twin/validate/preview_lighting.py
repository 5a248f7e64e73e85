"""The light of the BTF preview (``spectwin btf render``): two presets and a user's
environment map.

- ``studio``: three square area lights (key, fill, rim) of the 3000 K quartz tungsten halogen
  lamp (:class:`twin.components.lamps.QTHLamp`) over a dark grey backdrop (reflectance 0.05:
  a floor under the sample and a wall behind it);
- ``daylight``: a CIE D65 sky, brighter towards the horizon (a lat-long map, black below it),
  and a sun of the same spectrum, a directional light 45 degrees high, over a grey ground
  (reflectance 0.2);
- an environment: a lat-long OpenEXR map, spectral (Fichet et al. 2021, as
  :func:`recon.spectral_exr.read_spectral_exr` reads it) or RGB, whose linear RGB is upsampled
  to spectra by Jakob and Hanika (2019) times CIE D65 (a white of the map stays white), and said
  so. Its rows span the polar angles from the world's +z (up), its columns the azimuths from +x
  towards +y (:mod:`twin.render.plugins.spectral_envmap`). Maps higher than
  :data:`MAX_MAP_ROWS` rows are area-averaged down to it.

Each preset's lamps share one spectrum and render as one light group
(:mod:`twin.render.light_groups`); an environment's map carries its spectra itself.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID, QTHLamp, cie_illuminant
from twin.render.light_groups import LightGroup
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.spectra import irregular_spectrum
from twin.render.transforms import look_at, rotate, scale, translate
from twin.validate.preview_geometry import GROUND_Z_M

__all__ = [
    "MAX_MAP_ROWS",
    "PRESETS",
    "RGB_MAP_NOTE",
    "PreviewLighting",
    "environment_lighting",
    "map_lighting",
    "radiance_from_linear_srgb",
    "read_environment",
]

MAX_MAP_ROWS = 256
_EXR_MAGIC = b"\x76\x2f\x31\x01"
_CONSTANT = WavelengthGrid(np.array([400.0, 720.0]))
"""Grid of a map of flat spectra (the light group carries the spectrum)."""


@dataclass(frozen=True)
class PreviewLighting:
    """A preview's light and surroundings.

    ``entries``: scene entries (backdrop, emitters of flat spectrum in ``groups``' entries, or
    an environment with its own spectra); ``groups``: the lamps by spectrum; ``white``: the
    light's spectrum for the PNG's white balance; ``lamps``: name and position (m) of each small
    lamp, ``sun``: name and unit direction towards each distant light; ``sky``: unit directions
    ``(m, 3)`` and weights ``(m,)`` (radiance times solid angle) of the map's pixels;
    ``description``: one line; ``note``: what became of an RGB map, or ``None``.
    """

    entries: dict[str, object]
    groups: tuple[LightGroup, ...]
    white: SampledSpectra
    description: str
    lamps: dict[str, np.ndarray] = field(default_factory=dict)
    sun: dict[str, np.ndarray] = field(default_factory=dict)
    sky: tuple[np.ndarray, np.ndarray] | None = None
    note: str | None = None


def _diffuse(reflectance: float) -> dict[str, object]:
    flat = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, reflectance))
    return {"type": "diffuse", "reflectance": irregular_spectrum(flat)}


def _flat(value: float) -> dict[str, str]:
    return irregular_spectrum(SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, value)))


def _ground(reflectance: float) -> dict[str, object]:
    return {
        "type": "rectangle",
        "to_world": translate([0.0, 0.0, GROUND_Z_M]) @ scale(2.0),
        "bsdf": _diffuse(reflectance),
    }


def _map_directions(spectral_map: SpectralMap) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions of the map's pixel centres and their weights (band-mean radiance times
    solid angle), flattened."""
    height, width = spectral_map.radiance.shape[:2]
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = (np.arange(width) + 0.5) * 2 * np.pi / width
    theta, phi = np.meshgrid(theta, phi, indexing="ij")
    directions = np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1
    )
    weights = spectral_map.radiance.mean(axis=2) * spectral_map.solid_angles()
    return directions.reshape(-1, 3), weights.ravel()


def _d65(grid: WavelengthGrid) -> SampledSpectra:
    """CIE D65 on ``grid`` (held constant beyond its 300-780 nm table), peak 1."""
    d65 = resample(cie_illuminant("D65", DEFAULT_GRID), grid, out_of_range="clamp").values
    return SampledSpectra(grid, d65 / d65.max())


def studio() -> PreviewLighting:
    """Three QTH area lights over a dark grey backdrop (module docstring)."""
    spectrum = QTHLamp().relative_spectrum(FINE_GRID.wavelengths_nm)
    halogen = SampledSpectra(FINE_GRID, spectrum / spectrum.max())
    lamps = {
        "key": (np.array([0.30, -0.35, 0.40]), 40.0),
        "fill": (np.array([-0.45, -0.25, 0.20]), 15.0),
        "rim": (np.array([-0.10, 0.40, 0.35]), 30.0),
    }
    emitters = {
        f"lamp_{name}": {
            "type": "rectangle",
            "to_world": look_at(origin=position.tolist(), target=[0, 0, 0], up=[0, 0, 1])
            @ scale(0.05),
            "emitter": {"type": "area", "radiance": _flat(radiance)},
        }
        for name, (position, radiance) in lamps.items()
    }
    backdrop: dict[str, object] = {
        "floor": _ground(0.05),
        "backdrop": {
            "type": "rectangle",
            "to_world": translate([0.0, 0.35, 0.0]) @ rotate([1, 0, 0], 90) @ scale(2.0),
            "bsdf": _diffuse(0.05),
        },
    }
    return PreviewLighting(
        entries=backdrop,
        groups=(LightGroup("halogen lamps", emitters, halogen),),
        white=halogen,
        description="studio: three 3000 K halogen area lights over a dark grey backdrop",
        lamps={name: position for name, (position, _) in lamps.items()},
    )


def daylight() -> PreviewLighting:
    """A D65 sky and sun over a grey ground (module docstring)."""
    height = 32
    theta = (np.arange(height) + 0.5) * np.pi / height
    sky_rows = np.where(theta < np.pi / 2, 0.6 + 0.4 * (1 - np.cos(theta)), 0.0)
    radiance = np.repeat(sky_rows[:, None, None], 2 * height, axis=1).repeat(2, axis=2)
    sky = SpectralMap(radiance, _CONSTANT)
    towards_sun = np.array([0.5, -0.5, np.sqrt(0.5)])
    emitters = {
        "sky": spectral_envmap(sky),
        "sun": {
            "type": "directional",
            "direction": (-towards_sun).tolist(),
            "irradiance": _flat(8.0),
        },
    }
    d65 = _d65(FINE_GRID)
    return PreviewLighting(
        entries={"ground": _ground(0.2)},
        groups=(LightGroup("daylight", emitters, d65),),
        white=d65,
        description="daylight: a CIE D65 sky and a sun 45 degrees high over a grey ground",
        sun={"sun": towards_sun},
        sky=_map_directions(sky),
    )


PRESETS: dict[str, Callable[[], PreviewLighting]] = {"studio": studio, "daylight": daylight}
"""The preset lights by name (``--preset``)."""


def _reduced(cube: np.ndarray) -> np.ndarray:
    """``cube`` ``(H, W, K)`` area-averaged by a whole factor to at most MAX_MAP_ROWS rows."""
    factor = int(np.ceil(cube.shape[0] / MAX_MAP_ROWS))
    if factor <= 1:
        return cube
    height, width = cube.shape[0] // factor, cube.shape[1] // factor
    cropped = cube[: height * factor, : width * factor]
    return cropped.reshape(height, factor, width, factor, -1).mean(axis=(1, 3))


def _require_lat_long(path: Path, shape: tuple[int, ...]) -> None:
    height, width = shape[:2]
    if width != 2 * height:
        raise InputError(
            f"--environment {path}: {width} x {height} pixels; expected a lat-long map twice as "
            "wide as high"
        )


RGB_MAP_NOTE = "RGB map upsampled to spectra by Jakob 2019 times CIE D65"


def radiance_from_linear_srgb(linear: np.ndarray) -> np.ndarray:
    """Spectral radiance ``(..., K)`` on ``DEFAULT_GRID`` of linear sRGB radiance ``(..., 3)``:
    its reflectance by Jakob and Hanika (2019) times CIE D65 (peak 1), so that a white of the
    map stays white."""
    from recon.rgb_upsampling import upsample_srgb

    reflectance = upsample_srgb(np.maximum(linear, 0.0), "jakob2019").values
    return np.asarray(reflectance * _d65(DEFAULT_GRID).values, np.float64)


def read_environment(path: str | Path) -> tuple[SpectralMap, str | None]:
    """Read a lat-long environment map (module docstring).

    Parameters
    ----------
    path
        An OpenEXR file, spectral or RGB (linear), twice as wide as high.

    Returns
    -------
    tuple of SpectralMap and str or None
        The map, and for an RGB map how it was upsampled (``None`` for a spectral map).

    Raises
    ------
    InputError
        If the file is missing, not an OpenEXR file, not 2:1, or holds negative or non-finite
        radiance.
    """
    from recon.image_spectralization import read_linear_rgb
    from recon.rgb_upsampling import reduce_image
    from recon.spectral_exr import read_spectral_exr, read_spectral_layout

    path = Path(path)
    if not path.is_file():
        raise InputError(f"--environment {path}: no such file")
    with path.open("rb") as handle:
        if handle.read(4) != _EXR_MAGIC:
            raise InputError(f"--environment {path}: not an OpenEXR file; expected a lat-long map")
    try:
        layout = read_spectral_layout(path)
    except InputError:  # no spectral channels: an RGB map
        layout = None
    if layout is not None:
        _require_lat_long(path, layout.shape)
        image = read_spectral_exr(path)
        cube, grid = _reduced(np.asarray(image.cube, np.float64)), image.grid
        regular = WavelengthGrid.regular(
            float(grid.wavelengths_nm[0]),
            float(grid.wavelengths_nm[-1]),
            float(np.min(np.diff(grid.wavelengths_nm))) if grid.size > 1 else 1.0,
        )
        if grid.size > 1 and regular != grid:
            cube, grid = resample(SampledSpectra(grid, cube), regular).values, regular
        note = None
    else:
        linear = read_linear_rgb(path).values
        _require_lat_long(path, linear.shape)
        linear, _ = reduce_image(np.asarray(linear, np.float64), 2 * MAX_MAP_ROWS)
        cube, grid = radiance_from_linear_srgb(linear), DEFAULT_GRID
        note = RGB_MAP_NOTE
    try:
        return SpectralMap(np.asarray(cube, np.float64), grid), note
    except InputError as error:
        raise InputError(f"--environment {path}: {error}") from None


def map_lighting(
    spectral_map: SpectralMap, description: str, note: str | None = None
) -> PreviewLighting:
    """The light of a lat-long map: the map as the environment, its mean radiance as the white,
    its pixels as the sky."""
    white = spectral_map.radiance.reshape(-1, spectral_map.grid.size)
    weights = spectral_map.solid_angles().ravel()
    mean = weights @ white / weights.sum()
    return PreviewLighting(
        entries={"environment": spectral_envmap(spectral_map)},
        groups=(),
        white=SampledSpectra(spectral_map.grid, mean),
        description=description,
        sky=_map_directions(spectral_map),
        note=note,
    )


def environment_lighting(path: str | Path) -> PreviewLighting:
    """The light of a lat-long environment map at ``path`` (:func:`read_environment`)."""
    spectral_map, note = read_environment(path)
    return map_lighting(spectral_map, f"environment {Path(path).name}", note)
