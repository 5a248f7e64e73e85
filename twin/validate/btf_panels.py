"""Panels (b) and (c) of a rendering validation (thesis 4.2, Figure 4.6): a measured BTF on the
sample's square under a spectral environment map, seen by a camera.

- Spectral rendering: the BTF (:mod:`twin.render.plugins.btf_bsdf`) under the map, recorded
  through the camera's channel responses (a ``specfilm``).
- RGB rendering, the way an RGB pipeline renders: BTF and map reduced to the camera's three
  channels first (reflectance under equal energy, a perfect white = 1; radiance integrated
  against each channel's response), one rendering per channel.

Both use the same camera, samples and seed: with the same map, two BTFs are rendered with the
same random numbers (the BSDF samples the cosine hemisphere whatever its values), so their
difference is the BTFs'. The square lies in its reference plane z = 0, the plane the BTF's
textures are rectified to (the holder's marks, the truth's sample plane); the parallax of a
material's relief is in the view-dependent textures.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from recon.spectra import SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.render.light_groups import render_lit
from twin.render.plugins.btf_bsdf import BTFTable, CompressedTable, btf_bsdf
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.transforms import scale

__all__ = ["PANEL_SEED", "render_btf_in_channels", "render_btf_spectral", "sample_square"]

PANEL_SEED = 3
"""Seed of every panel's rendering."""

_CONSTANT = WavelengthGrid(np.array([400.0, 720.0]))
"""Grid of the one-channel tables and maps: the same value at both ends, constant."""

ResponsesOn = Callable[[WavelengthGrid], np.ndarray]
"""``responses_on(grid)``: three channel responses ``(3, K)`` on ``grid``."""


def sample_square(size_m: float) -> dict[str, object]:
    """The BTF's square of side ``size_m`` in its reference plane z = 0, facing +z."""
    return {"type": "rectangle", "to_world": scale(size_m / 2)}


def render_btf_spectral(
    camera,
    table: BTFTable | CompressedTable,
    environment: SpectralMap,
    size_m: float,
    channels: SampledSpectra,
    *,
    spp: int,
) -> np.ndarray:
    """The BTF on the square under ``environment``, recorded through ``channels``;
    ``(H, W, n_channels)``. ``camera``: anything with ``mitsuba_sensor(channels, spp)``."""
    entries = {
        "environment": spectral_envmap(environment),
        "sample": {**sample_square(size_m), "bsdf": btf_bsdf(table)},
    }
    return render_lit(camera, channels, entries, spp=spp, seed=PANEL_SEED)


def _channel_tables(table: BTFTable | CompressedTable, responses: np.ndarray) -> list[BTFTable]:
    """The BTF as three one-channel tables of reflectance in ``responses``' channels (equal
    energy, white = 1); a compressed BTF is decoded one combination at a time. Specular lobes,
    spectrally flat, are the same in every channel."""
    weights = responses / responses.sum(axis=1, keepdims=True)
    values = np.maximum(
        np.stack(
            [
                np.stack([table.texture(i, j) @ weights.T for j in range(len(table.view_dirs))])
                for i in range(len(table.light_dirs))
            ]
        ),
        0.0,
    )
    return [
        BTFTable(
            table.light_dirs,
            table.view_dirs,
            values[..., [c, c]].astype(np.float32),
            _CONSTANT,
            table.lobes,
        )
        for c in range(3)
    ]


def _channel_maps(environment: SpectralMap, responses: np.ndarray) -> list[SpectralMap]:
    """The map as three one-channel maps of radiance integrated against ``responses``."""
    step = environment.grid.wavelengths_nm[1] - environment.grid.wavelengths_nm[0]
    values = np.maximum(np.einsum("hwk,ck->hwc", environment.radiance, responses), 0)
    return [SpectralMap(values[..., [c, c]] * step, _CONSTANT) for c in range(3)]


def _flat_film() -> SampledSpectra:
    """One channel of unit area over 400-720 nm: a one-band rendering's value times 1."""
    inside = (FINE_GRID.wavelengths_nm >= 400) & (FINE_GRID.wavelengths_nm <= 720)
    return SampledSpectra(FINE_GRID, (inside / 320.0)[None, :], ("flat",))


def render_btf_in_channels(
    camera,
    table: BTFTable | CompressedTable,
    environment: SpectralMap,
    size_m: float,
    responses_on: ResponsesOn,
    *,
    spp: int,
) -> np.ndarray:
    """The RGB rendering (module docstring) in the channels of ``responses_on``;
    ``(H, W, 3)``, a perfect white diffuser's value the map's radiance in each channel."""
    channels = []
    for channel_table, channel_map in zip(
        _channel_tables(table, responses_on(table.grid)),
        _channel_maps(environment, responses_on(environment.grid)),
        strict=True,
    ):
        entries = {
            "environment": spectral_envmap(channel_map),
            "sample": {**sample_square(size_m), "bsdf": btf_bsdf(channel_table)},
        }
        channels.append(render_lit(camera, _flat_film(), entries, spp=spp, seed=PANEL_SEED)[..., 0])
    return np.stack(channels, -1)
