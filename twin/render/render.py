"""Render a Mitsuba scene to a float64 NumPy image (twin's one call of ``mi.render``)."""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from recon.errors import InputError
from twin.render.variant import activate

__all__ = ["render_scene"]


def render_scene(scene: dict | mi.Scene, seed: int = 0, spp: int | None = None) -> np.ndarray:
    """Render ``scene`` with its first sensor and integrator.

    Parameters
    ----------
    scene : dict or mitsuba.Scene
        A scene dict (loaded with ``mi.load_dict``) or an already loaded scene.
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
        scene = mi.load_dict(scene)
    # Mitsuba's stubs type load_dict's result as dict | Scene and the seed as UInt32 (an int is
    # taken)
    image = mi.render(scene, seed=seed, spp=0 if spp is None else int(spp))  # type: ignore[arg-type]
    return np.array(image, np.float64)
