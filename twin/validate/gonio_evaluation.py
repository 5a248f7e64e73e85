"""A measured (virtual) BTF against the twin's truth: per-field spectra and registered corners.

The twin's true BTF (:func:`twin.render.truth.truth_btf`) is rendered for the BTF store's direction
pairs at its texel resolution, rectified to the sample plane like a measured texture. The
comparison is made per chart field (the parts named ``field_*`` of the material): each field's
interior (its top face shifted by the view's parallax, shrunk to ``interior`` of its width so
that registration blur and the few tenths of a millimetre between the registration plane and
the truth's plane stay outside) gives one mean spectrum per pair in the measurement and in the
truth, and Eq. 6.8 compares the two. Glossy fields (a coating with a roughness) are reported
apart: their highlights depend on sub-degree direction errors and saturate the camera.

The registered corners stored with the BTF are compared with the projections of the marks'
corners for the poses the robot actually reached in the capture session.
:func:`write_gonio_figure` draws the comparison (``spectwin evaluate``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from hwbridge.schema import GonioRigAttrs, recorded
from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.metrics import relative_error
from recon.preview import spectral_to_srgb
from recon.spectra import SampledSpectra
from twin.gonio.capture import GonioPairs, actual_poses, texture_corners_world
from twin.gonio.render import gonio_camera
from twin.materials import load_material
from twin.materials.chart_fields import FieldMasks, field_masks
from twin.render.truth import truth_btf
from twin.rigs.hemisphere import spherical_deg
from twin.rigs.rig_config import GonioConfig
from twin.sensor.band_weights import instrument_passbands
from twin.validate.gonio_texel_evaluation import GonioTexelEvaluation, compare_texels

__all__ = [
    "FieldMasks",
    "capture_rig",
    "GonioEvaluation",
    "evaluate_gonio",
    "field_masks",
    "pair_label",
    "write_gonio_figure",
]


@dataclass(frozen=True)
class GonioEvaluation:
    """Per written pair and field: Eq. 6.8 of the field means, %; corner errors, px."""

    field_names: tuple[str, ...]
    glossy: np.ndarray
    pairs: np.ndarray  # (n_pairs,) the BTF store's indices of the compared (written) pairs
    field_error: np.ndarray  # (n_pairs, n_fields)
    texel_error: np.ndarray  # (n_pairs, n_fields): mean over the interior of per-texel Eq. 6.8
    corner_error_px: np.ndarray  # (n_pairs, 4)
    measured_means: np.ndarray  # (n_pairs, n_fields, K)
    truth_means: np.ndarray

    def summary(self) -> dict[str, Any]:
        matte = ~self.glossy
        return {
            "pairs_compared": int(self.field_error.shape[0]),
            "mean_relative_error_matte_fields_pct": float(self.field_error[:, matte].mean()),
            "max_relative_error_matte_fields_pct": float(self.field_error[:, matte].max()),
            "mean_relative_error_glossy_fields_pct": float(self.field_error[:, ~matte].mean()),
            "per_texel_error_matte_fields_pct": float(self.texel_error[:, matte].mean()),
            "max_corner_error_px": float(self.corner_error_px.max()),
            "mean_corner_error_px": float(self.corner_error_px.mean()),
            "per_field_pct": {
                name: round(float(value), 3)
                for name, value in zip(self.field_names, self.field_error.mean(axis=0), strict=True)
            },
        }


def capture_rig(capture: CaptureStore) -> GonioConfig:
    """The rig model a twin measurement run was made with (the ``config`` of its rig
    attribute)."""
    return GonioConfig.model_validate(capture.rig_attrs(GonioRigAttrs).config)


def _true_corners(capture: CaptureStore, btf: BTFStore) -> np.ndarray:
    config = capture_rig(capture)
    rig = capture.rig_attrs(GonioRigAttrs)
    pairs = GonioPairs(config, btf.light_dirs, btf.view_dirs)
    poses = actual_poses(config, pairs.poses, capture.metadata.seed)
    pixels = int(recorded(rig.sensor_px, f"{capture.path}: rig.sensor_px"))
    window = rig.window_px
    return np.stack(
        [
            gonio_camera(config, pose.rail_deg, pixels, window).project(texture_corners_world(pose))
            for pose in poses
        ]
    )


def evaluate_gonio(
    btf_path: str | Path,
    *,
    spp: int = 64,
    interior: float = 0.6,
    passbands: SampledSpectra | None = None,
    progress: bool = False,
) -> GonioEvaluation | GonioTexelEvaluation:
    """Compare a BTF store made by ``spectwin process`` with the twin's truth (module docstring;
    a material without chart fields texel by texel, :mod:`twin.validate.gonio_texel_evaluation`).

    The capture store named in the BTF's provenance supplies the session seed (the robot's
    actual poses), the rendered window and the rig model. Pairs not written (unregistered) are
    left out and counted in :meth:`GonioEvaluation.summary`. The truth's bands average the
    reflectance with ``passbands`` (rows of unit area on ``FINE_GRID``); by default with the
    capturing instrument's own weights (:func:`instrument_passbands`), so that only noise,
    registration and calibration differ; narrow ``passbands`` at the band centres make the
    filter's bandwidth part of the error.
    """
    if isinstance(spp, bool) or not isinstance(spp, int | np.integer) or spp < 1:
        raise InputError(f"spp: expected a positive number of samples, got {spp!r}")
    btf = BTFStore.open(btf_path)
    written = np.flatnonzero(btf.written())
    if not written.size:
        raise InputError(
            f"{btf_path}: no direction pair is written yet; finish the BTF with spectwin "
            "process --resume"
        )
    source = btf.metadata.source_capture
    if not source:
        raise InputError(
            f"{btf_path}: records no source capture; evaluate compares BTFs made by spectwin "
            "process from a twin capture"
        )
    try:
        capture = CaptureStore.open(source)
    except InputError as error:
        raise InputError(
            f"{btf_path}: the capture store it was processed from is needed: {error}"
        ) from None
    material = load_material(btf.material)
    texels = btf.texels[0]
    chart = any(part.name.startswith("field_") for part in material.parts)
    for pair in written if chart else ():
        fields = field_masks(material, btf.view_dirs[pair], texels, interior=interior)
        if not fields.masks.any(axis=(1, 2)).all():
            raise InputError(
                f"{btf_path}: at {texels} texels some chart fields have no interior texel to "
                "compare; process the capture again with --texels 16 or more"
            )
    truth = truth_btf(
        material,
        btf.light_dirs[written],
        btf.view_dirs[written],
        texels=texels,
        passbands=instrument_passbands(capture_rig(capture)) if passbands is None else passbands,
        spp=spp,
    )
    corners = btf.corners_xy()[written]
    corner_error = np.linalg.norm(corners - _true_corners(capture, btf)[written], axis=2)
    if not chart:
        measured = np.stack([btf.read_pair(int(pair), allow_incomplete=True) for pair in written])
        return compare_texels(written, measured, truth, btf.grid, corner_error)
    field_means, truth_means, texel_errors = [], [], []
    for index, pair in enumerate(written):  # one pair in memory at a time
        measured = btf.read_pair(int(pair), allow_incomplete=True)
        fields = field_masks(material, btf.view_dirs[pair], texels, interior=interior)
        field_means.append(fields.means(measured))
        truth_means.append(fields.means(truth[index]))
        per_texel = relative_error(measured, truth[index])
        texel_errors.append([per_texel[mask].mean() for mask in fields.masks])
    measured_fields, true_fields = np.array(field_means), np.array(truth_means)
    return GonioEvaluation(
        fields.names,
        fields.glossy,
        written,
        relative_error(measured_fields, true_fields),
        np.array(texel_errors),
        corner_error,
        measured_fields,
        true_fields,
    )


def pair_label(btf: BTFStore, pair: int) -> str:
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
    figure = Figure(figsize=(13, 9))
    axes = figure.subplots(2, 2)
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
        title=f"lines: truth, dots: measured; {pair_label(btf, evaluation.pairs[oblique])}",
    )
    axes[1, 0].legend(fontsize=8)
    shown = [evaluation.pairs[int(np.argmin(np.arccos(views[:, 2])))], evaluation.pairs[oblique]]
    previews = [
        spectral_to_srgb(btf.read_pair(pair, allow_incomplete=True), btf.grid) for pair in shown
    ]
    axes[1, 1].imshow(np.concatenate(previews, axis=1))
    axes[1, 1].set_title(f"measured textures: {pair_label(btf, shown[0])} | oblique", fontsize=9)
    axes[1, 1].axis("off")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    return path
