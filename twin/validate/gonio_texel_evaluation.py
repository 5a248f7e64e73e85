"""A measured (virtual) gonio BTF of a material without chart fields against the twin's truth,
texel by texel: a user's sample or a built-in such as the Lego bricks.

Both the measurement and the truth (:func:`twin.render.truth.truth_btf` at the store's pairs and
texels, bands weighted like the capturing instrument) are compared as reflectance factors (pi x
the BTF's 1/sr) over the texels that show the material (a true band mean of at least
:data:`twin.materials.textures.MATERIAL_TEXEL_REFLECTANCE`) away from the texture's border
(:data:`BORDER_TEXELS`, where the registration's blur mixes the holder in): Eq. 6.8 and Delta E94
(the thesis's ten illuminants) per texel, their means per pair and over all.
:func:`write_texel_figure` draws them with the worst pair's error map and textures.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from recon.preview import spectral_to_srgb
from recon.spectra import WavelengthGrid
from twin.materials.textures import MATERIAL_TEXEL_REFLECTANCE
from twin.validate.texel_errors import texel_errors

__all__ = ["BORDER_TEXELS", "GonioTexelEvaluation", "compare_texels", "write_texel_figure"]

BORDER_TEXELS = 2
"""Texels along each edge of the texture left out of the comparison."""


@dataclass(frozen=True)
class GonioTexelEvaluation:
    """Per compared pair and texel: Eq. 6.8 (%) and Delta E94 (NaN off the material), their
    means per pair, the registered corners' errors (px) and both textures (reflectance
    factors)."""

    pairs: np.ndarray  # (n_pairs,) the BTF store's indices of the compared (written) pairs
    relative_pct: np.ndarray  # (n_pairs, H * W)
    delta_e94: np.ndarray  # (n_pairs, H * W)
    pair_relative_pct: np.ndarray  # (n_pairs,)
    pair_delta_e94: np.ndarray  # (n_pairs,)
    corner_error_px: np.ndarray  # (n_pairs, 4)
    measured: np.ndarray  # (n_pairs, H, W, K)
    truth: np.ndarray
    grid: WavelengthGrid

    def summary(self) -> dict[str, Any]:
        relative, colour = self.relative_pct, self.delta_e94
        return {
            "pairs_compared": int(self.pairs.size),
            "texels_compared": int(np.isfinite(relative).sum()),
            "mean_relative_error_texels_pct": float(np.nanmean(relative)),
            "median_relative_error_texels_pct": float(np.nanmedian(relative)),
            "p95_relative_error_texels_pct": float(np.nanpercentile(relative, 95)),
            "mean_delta_e94_texels": float(np.nanmean(colour)),
            "median_delta_e94_texels": float(np.nanmedian(colour)),
            "p95_delta_e94_texels": float(np.nanpercentile(colour, 95)),
            "max_corner_error_px": float(self.corner_error_px.max()),
            "mean_corner_error_px": float(self.corner_error_px.mean()),
        }


def compare_texels(
    pairs: np.ndarray,
    measured: np.ndarray,
    truth: np.ndarray,
    grid: WavelengthGrid,
    corner_error_px: np.ndarray,
) -> GonioTexelEvaluation:
    """The evaluation of BTF textures ``measured`` against ``truth`` (both ``(n_pairs, H, W,
    K)`` in 1/sr) of the store's ``pairs``."""
    measured, truth = np.pi * measured.astype(np.float64), np.pi * truth.astype(np.float64)
    shows = truth.mean(axis=-1) >= MATERIAL_TEXEL_REFLECTANCE
    shows[:, :BORDER_TEXELS] = shows[:, -BORDER_TEXELS:] = False
    shows[:, :, :BORDER_TEXELS] = shows[:, :, -BORDER_TEXELS:] = False
    errors = texel_errors(measured, truth, grid, shows)
    return GonioTexelEvaluation(pairs, *errors, corner_error_px, measured, truth, grid)


def write_texel_figure(evaluation: GonioTexelEvaluation, labels: list[str], path: str | Path):
    """Four panels: Eq. 6.8 and Delta E94 per pair (``labels``), the per-texel Eq. 6.8
    histogram, the worst pair's error map, and its measured and true textures (sRGB previews
    under equal energy)."""
    path = Path(path)
    figure = Figure(figsize=(13, 9))
    axes = figure.subplots(2, 2)
    index = np.arange(evaluation.pairs.size)
    axes[0, 0].bar(index - 0.2, evaluation.pair_relative_pct, 0.4, label="Eq. 6.8, %")
    axes[0, 0].bar(index + 0.2, evaluation.pair_delta_e94, 0.4, label="Delta E94")
    axes[0, 0].set_xticks(index, labels, rotation=30, ha="right", fontsize=7)
    axes[0, 0].set(title="mean over the material's texels, per direction pair")
    axes[0, 0].legend(fontsize=8)
    finite = evaluation.relative_pct[np.isfinite(evaluation.relative_pct)]
    axes[0, 1].hist(finite, bins=50, color="tab:blue")
    axes[0, 1].set(
        xlabel="relative error per texel (Eq. 6.8), %",
        ylabel="texel x pair count",
        title=f"mean {finite.mean():.2f} %, 95th percentile {np.percentile(finite, 95):.2f} %",
    )
    worst = int(np.nanargmax(evaluation.pair_relative_pct))
    side = evaluation.measured.shape[1]
    shown = axes[1, 0].imshow(evaluation.relative_pct[worst].reshape(side, side), cmap="magma")
    figure.colorbar(shown, ax=axes[1, 0], label="Eq. 6.8, %")
    axes[1, 0].set_title(f"worst pair: {labels[worst]}", fontsize=9)
    axes[1, 0].axis("off")
    previews = [
        spectral_to_srgb(texture[worst], evaluation.grid)
        for texture in (evaluation.measured, evaluation.truth)
    ]
    axes[1, 1].imshow(np.concatenate(previews, axis=1))
    axes[1, 1].set_title("measured | truth (sRGB preview)", fontsize=9)
    axes[1, 1].axis("off")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    return path
