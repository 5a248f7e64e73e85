"""Rendering scenes lit by lamps of a few spectral types, one type at a time.

Light transport is linear in the emitted spectrum, wavelength by wavelength: a camera channel of
response :math:`c(\\lambda)` looking at emitters of spectrum :math:`S(\\lambda)` records
:math:`\\int c(\\lambda) S(\\lambda) T(\\lambda) d\\lambda`, with :math:`T` the transport of a
flat unit emitter. The same expectation comes from emitters of flat unit spectrum seen through
the channel :math:`c S`, and then Mitsuba samples wavelengths in proportion to :math:`c S`
instead of :math:`c` alone. For spiky lamps (HMI and fluorescent emission lines) this removes
most of the per-band Monte Carlo noise (thesis 4.2's room: the band noise of a 10 nm band
under office fluorescent tubes drops from several percent to well below one).

A scene with several lamp types (halogen spots and fluorescent tubes) is rendered once per
:class:`LightGroup` (the emitters that share one spectrum), the other groups' lamps present as
dark shapes, and the renders are summed. Group ``i`` is rendered with its own seed,
:func:`group_seed` of the render's seed and ``i``, so that the groups' noise is independent and
each group's image is fixed by the seed and its place in the list alone. Each
channel is normalized to unit area for the render and scaled back, so that every channel gets an
equal share of the wavelength samples.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.render.render import render_scene

__all__ = ["LightGroup", "group_seed", "lamp_weighted_channels", "render_lit"]


@dataclass(frozen=True)
class LightGroup:
    """Emitters sharing one emission spectrum.

    ``entries`` are Mitsuba scene entries whose emitters emit a flat spectrum (their own scale
    only); ``spectrum`` is the spectrum all of them share, on the channels' grid.
    """

    name: str
    entries: dict[str, Any]
    spectrum: SampledSpectra


def group_seed(seed: int, index: int) -> int:
    """The seed of light group ``index`` in a render seeded with ``seed``.

    Parameters
    ----------
    seed : int
        The render's seed (non-negative).
    index : int
        The group's place in the list of groups.

    Returns
    -------
    int
        A 32-bit seed drawn from ``numpy.random.SeedSequence([seed, index])``: the same for the
        same pair, independent streams for different groups.
    """
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1, np.uint32)[0])


def lamp_weighted_channels(
    channels: SampledSpectra, spectrum: SampledSpectra
) -> tuple[SampledSpectra, np.ndarray]:
    """Channel responses times ``spectrum``, each normalized to unit area, and the areas
    ``(n_channels,)`` to multiply a render with (module docstring)."""
    if spectrum.grid != channels.grid:
        raise InputError(
            f"spectrum: expected the channels' grid ({channels.grid.describe()}), got "
            f"{spectrum.grid.describe()}"
        )
    weighted = np.atleast_2d(channels.values * np.ravel(spectrum.values))
    areas = np.trapezoid(weighted, channels.grid.wavelengths_nm, axis=-1)
    areas = np.where(areas > 0, areas, 1.0)
    return SampledSpectra(channels.grid, weighted / areas[:, None], channels.names), areas


def render_lit(
    camera,
    channels: SampledSpectra,
    entries: dict[str, Any],
    groups: Sequence[LightGroup] = (),
    *,
    spp: int = 64,
    seed: int = 0,
    max_depth: int = 4,
) -> np.ndarray:
    """Render ``entries`` with ``camera`` (anything with ``mitsuba_sensor(channels, spp)``) lit
    by ``groups``, one render per group (the others' lamps dark) summed; ``(H, W, n_channels)``.

    Without groups, ``entries`` must hold their own emitters, and are rendered once as they are,
    with ``seed``; group ``i`` is rendered with :func:`group_seed` ``(seed, i)``. The same
    arguments give the same image bit for bit (:mod:`twin.render.render`).
    """

    def render(group_entries: dict[str, Any], film: SampledSpectra, seed: int) -> np.ndarray:
        scene = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": max_depth},
            "sensor": camera.mitsuba_sensor(film, spp),
            **entries,
            **group_entries,
        }
        return render_scene(scene, seed)

    if not groups:
        return render({}, channels, seed)
    total: np.ndarray | float = 0.0
    for index, group in enumerate(groups):
        film, areas = lamp_weighted_channels(channels, group.spectrum)
        dark = {
            name: {key: value for key, value in entry.items() if key != "emitter"}
            for other in groups
            if other is not group
            for name, entry in other.entries.items()
        }
        total = total + render({**dark, **group.entries}, film, group_seed(seed, index)) * areas
    return np.asarray(total)
