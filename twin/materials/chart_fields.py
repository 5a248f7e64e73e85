"""The fields of a chart material in texel space: their interiors as one view sees them.

A chart's field (the parts named ``field_*``) lies on the sample, its top face a little above
the plate; a texture on the plate (the twin's truth's, a processed BTF's) sees that face shifted
by the view's parallax. The interiors, shrunk so that registration blur and the edges stay
outside, are where measured and true spectra are compared (:mod:`twin.validate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.materials import Material

__all__ = ["FieldMasks", "field_masks"]


@dataclass(frozen=True)
class FieldMasks:
    """Interior masks ``(n_fields, H, W)`` of a chart's fields for one view, and their names."""

    names: tuple[str, ...]
    glossy: np.ndarray
    masks: np.ndarray

    def means(self, texture: np.ndarray, fields: np.ndarray | None = None) -> np.ndarray:
        """The mean spectrum ``(n, K)`` of a texture ``(H, W, K)`` in each field interior, or in
        those of the indices ``fields`` (each must hold texels)."""
        masks = self.masks if fields is None else self.masks[fields]
        return np.array([texture[mask].mean(axis=0) for mask in masks])


def field_masks(
    material: Material, view_dir: np.ndarray, texels: int, *, interior: float = 0.6
) -> FieldMasks:
    """Field interiors in texel space for a view (texel ``(i, j)`` = sample
    ``x = -s/2 + (j + 0.5) s / n``, ``y = s/2 - (i + 0.5) s / n``, the truth's layout)."""
    size, parts = material.size_m, [p for p in material.parts if p.name.startswith("field_")]
    centres = (np.arange(texels) + 0.5) / texels * size - size / 2
    x, y = np.meshgrid(centres, -centres)
    masks = []
    for part in parts:
        (low, high) = part.mesh.bounds
        shift = high[2] * np.asarray(view_dir[:2]) / view_dir[2]
        middle = (low[:2] + high[:2]) / 2 - shift
        half = interior * (high[:2] - low[:2]) / 2
        masks.append((np.abs(x - middle[0]) < half[0]) & (np.abs(y - middle[1]) < half[1]))
    return FieldMasks(
        tuple(p.name for p in parts),
        np.array([p.roughness is not None for p in parts]),
        np.stack(masks),
    )
