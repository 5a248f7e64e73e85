"""Figures of a gonioreflectometer BTF against the twin's truth (``spectwin evaluate``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from recon.btf.store import BTFStore  # noqa: E402
from recon.preview import spectral_to_srgb  # noqa: E402
from twin.rigs.hemisphere import spherical_deg  # noqa: E402
from twin.validate.gonio_evaluation import GonioEvaluation  # noqa: E402

__all__ = ["write_gonio_figure"]


def _pair_label(btf: BTFStore, pair: int) -> str:
    (light_theta, light_phi), (view_theta, view_phi) = (
        spherical_deg(btf.light_dirs[pair]),
        spherical_deg(btf.view_dirs[pair]),
    )
    return (
        f"light ({light_theta:.0f}, {light_phi:.0f}) deg, view ({view_theta:.0f}, {view_phi:.0f})"
    )


def write_gonio_figure(evaluation: GonioEvaluation, btf: BTFStore, path: str | Path) -> Path:
    """Four panels: mean Eq. 6.8 error per field (matte and glossy), its distribution over the
    pairs, measured versus true field spectra of the most oblique pair, and that pair's measured
    texture next to a frontal one (sRGB previews of the reflectance under equal energy)."""
    path = Path(path)
    figure, axes = plt.subplots(2, 2, figsize=(13, 9))
    names = [name.replace("field_", "") for name in evaluation.field_names]
    colours = np.where(evaluation.glossy, "tab:orange", "tab:blue")
    axes[0, 0].bar(names, evaluation.field_error.mean(axis=0), color=colours)
    axes[0, 0].axhline(3.0, color="k", linestyle="--", linewidth=1)
    axes[0, 0].set(
        xlabel="field (orange: glossy)",
        ylabel="mean relative error (Eq. 6.8), %",
        title=f"per field, mean over {evaluation.field_error.shape[0]} direction pairs",
    )
    matte = evaluation.field_error[:, ~evaluation.glossy].ravel()
    axes[0, 1].hist(matte, bins=40, color="tab:blue")
    axes[0, 1].set(
        xlabel="relative error of a matte field's mean spectrum, %",
        ylabel="field x pair count",
        title=f"matte fields: mean {matte.mean():.2f} %, 95th percentile "
        f"{np.percentile(matte, 95):.2f} %",
    )
    views = btf.view_dirs[evaluation.pairs]
    oblique = int(np.argmax(np.arccos(views[:, 2])))
    wavelengths = btf.grid.wavelengths_nm
    for field in np.flatnonzero(~evaluation.glossy)[::3]:
        (line,) = axes[1, 0].plot(
            wavelengths, evaluation.truth_means[oblique, field], label=f"field {names[field]}"
        )
        axes[1, 0].plot(
            wavelengths, evaluation.measured_means[oblique, field], "o", color=line.get_color()
        )
    axes[1, 0].set(
        xlabel="wavelength, nm",
        ylabel="BRDF, 1/sr",
        title=f"lines: truth, dots: measured; {_pair_label(btf, evaluation.pairs[oblique])}",
    )
    axes[1, 0].legend(fontsize=8)
    shown = [evaluation.pairs[int(np.argmin(np.arccos(views[:, 2])))], evaluation.pairs[oblique]]
    previews = [
        spectral_to_srgb(btf.read_pair(pair, allow_incomplete=True), btf.grid) for pair in shown
    ]
    axes[1, 1].imshow(np.concatenate(previews, axis=1))
    axes[1, 1].set_title(f"measured textures: {_pair_label(btf, shown[0])} | oblique", fontsize=9)
    axes[1, 1].axis("off")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path
