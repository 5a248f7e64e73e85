"""Load Mitsuba scenes and render them to float64 NumPy images (twin's one call of ``mi.render``).

Scenes are loaded with Mitsuba's scene optimization off (``mi.load_dict(..., optimize=False)``):
with it on, Mitsuba 3.9 merges objects of identical definitions, and the order in which lamps of
one definition (the room's tubes, a rig's alike lamps) end up in the scene changed from one load
to the next, and with it which lamp drew which random numbers: the same scene and seed gave
different images (10 loads of four alike rectangle lamps gave 5 different images). Loaded without
it, the same scene and seed give the same image bit for bit, whatever Dr.Jit's thread count
(``tests/twin/render/test_render_determinism.py``).
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi
import numpy as np

from recon.errors import InputError
from twin.render.variant import activate

__all__ = ["load_scene", "render_scene"]


def load_scene(entries: dict) -> Any:
    """Load a scene dict (or any Mitsuba object's dict) the same way every time.

    Parameters
    ----------
    entries : dict
        The dict that ``mi.load_dict`` takes.

    Returns
    -------
    mitsuba.Scene or mitsuba.Object
        The loaded scene (or BSDF, ...), Mitsuba's scene optimization off (module docstring).
    """
    activate()
    return mi.load_dict(entries, optimize=False)


def render_scene(scene: dict | mi.Scene, seed: int = 0, spp: int | None = None) -> np.ndarray:
    """Render ``scene`` with its first sensor and integrator.

    Parameters
    ----------
    scene : dict or mitsuba.Scene
        A scene dict (loaded with :func:`load_scene`) or an already loaded scene.
    seed : int, optional
        Seed of the render's random numbers; the same seed gives the same image.
    spp : int, optional
        Samples per pixel, overriding the sensor's sampler (which ``None`` keeps).

    Returns
    -------
    numpy.ndarray
        The film's image ``(H, W, n_channels)``, float64.

    Raises
    ------
    InputError
        If ``spp`` is given and below 1.
    """
    if spp is not None and int(spp) < 1:
        raise InputError(f"spp: expected at least 1 sample per pixel, got {spp}")
    activate()
    if isinstance(scene, dict):
        scene = load_scene(scene)
    # Mitsuba's stubs type the seed as UInt32 (an int is taken)
    image = mi.render(scene, seed=seed, spp=0 if spp is None else int(spp))  # type: ignore[arg-type]
    return np.array(image, np.float64)
