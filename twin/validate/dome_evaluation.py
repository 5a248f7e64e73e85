"""A BTF processed from a dome run against the twin's truth (``spectwin evaluate``).

The truth (:func:`twin.render.truth.truth_btf`) is rendered at the BTF's direction pairs and
texels, of the sample on its holder as the dome holds it (the holder's white paper shows beside
a tall sample seen obliquely and lights its sides), each band weighted as the dome's spectral
camera defines it (LCTF x quantum efficiency x LED, :func:`spectral_passbands`: what its
calibration measures); both are compared as reflectance factors (pi x the BTF's 1/sr):

- materials with chart fields (``field_*``): per pair and diffuse field (the fields without
  gloss), the field's interior (:func:`twin.materials.chart_fields.field_masks`): Eq. 6.8
  and Delta E94 (the thesis's ten illuminants) of the interior's mean spectra, and their means
  over the interior's texels;
- other materials: per texel, over the texels that show the material (its own render, without
  the holder, at least :data:`twin.materials.textures.MATERIAL_TEXEL_REFLECTANCE`), in the pairs
  away from the mirror configuration (half vector more than :data:`SPECULAR_DEG` from the
  normal): there a glossy sample's highlight depends on the LED's and the camera's distance
  (a spot under the dome's LED 0.75 m away, the whole sample under the truth's distant light)
  and saturates the cameras.

Registration, two ways: the texture's corners stored with every pair against the projection of
the sample's square by the store's nominal camera (the twin's cameras are where the metadata
puts them), in pixels; and the texture's shift against the truth's
(``skimage.registration.phase_cross_correlation`` of their band means, to 1/20 texel), in
texels. :func:`write_dome_figure` draws it all.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from skimage.registration import phase_cross_correlation

from hwbridge.schema import recorded
from hwbridge.store import CaptureStore
from recon.btf.schema import BTFAttrs
from recon.btf.store import BTFStore
from recon.calibration.dome_capture import dome_rig
from recon.calibration.dome_geometric import CameraGeometry, stage_rotation
from recon.errors import InputError
from recon.metrics import delta_e94, relative_error
from recon.preview import spectral_to_srgb
from recon.spectra import SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.dome.capture import dome_cameras
from twin.materials import load_material
from twin.materials.chart_fields import field_masks
from twin.materials.sample_holder import holder_parts
from twin.materials.textures import MATERIAL_TEXEL_REFLECTANCE
from twin.render.truth import truth_btf
from twin.validate.texel_errors import texel_errors

__all__ = [
    "SPECULAR_DEG",
    "DomeEvaluation",
    "chart_field_errors",
    "evaluate_dome",
    "spectral_passbands",
    "write_dome_figure",
]

SPECULAR_DEG = 10.0
"""Pairs whose half vector lies within this of the normal are left out of the texel errors of
materials without chart fields (module docstring)."""


def spectral_passbands(bands_nm: np.ndarray) -> SampledSpectra:
    """The dome's spectral camera's bands as weights of unit area on ``FINE_GRID``: LCTF
    transmission x quantum efficiency x LED (:meth:`twin.dome.capture.DomeCameras
    .band_reflectance`'s weighting)."""
    cameras = dome_cameras(1, texel_px=2, bands_nm=np.asarray(bands_nm, np.float64))
    weights = cameras.spectral.electron_responses(FINE_GRID, cameras.bands).values
    weights = weights * cameras.led.values
    weights /= (weights * FINE_GRID.quadrature_weights()).sum(axis=1, keepdims=True)
    return SampledSpectra(FINE_GRID, weights)


@dataclass(frozen=True)
class DomeEvaluation:
    """A dome BTF against the truth: per compared pair its errors, registration and spectra.

    Attributes
    ----------
    material, chart
        The material and whether it has chart fields (then the errors are per diffuse field).
    pairs, cameras
        ``(n,)`` the BTF's indices of the compared pairs and their RGB cameras.
    relative_pct, delta_e94
        ``(n, m)`` Eq. 6.8 and Delta E94 per pair of the diffuse fields' mean spectra (chart)
        or of the material texels (``m`` texels, NaN where a texel shows no material).
    texel_relative_pct, texel_delta_e94
        ``(n,)`` their per-texel means over the diffuse fields' interiors or material texels.
    corner_error_px
        ``(n, 4)`` the stored texture corners against the nominal camera's projection.
    shift_texels
        ``(n,)`` the texture's shift against the truth's.
    measured, truth
        ``(n, H, W, K)`` reflectance factors.
    grid
        The bands.
    """

    material: str
    chart: bool
    pairs: np.ndarray
    cameras: np.ndarray
    relative_pct: np.ndarray
    delta_e94: np.ndarray
    texel_relative_pct: np.ndarray
    texel_delta_e94: np.ndarray
    corner_error_px: np.ndarray
    shift_texels: np.ndarray
    measured: np.ndarray
    truth: np.ndarray
    grid: WavelengthGrid

    def summary(self) -> dict[str, object]:
        what = "diffuse_fields" if self.chart else "material_texels"
        return {
            "material": self.material,
            "pairs_compared": int(self.pairs.size),
            f"mean_relative_error_{what}_pct": float(np.nanmean(self.relative_pct)),
            f"median_relative_error_{what}_pct": float(np.nanmedian(self.relative_pct)),
            f"p95_relative_error_{what}_pct": float(np.nanpercentile(self.relative_pct, 95)),
            f"mean_delta_e94_{what}": float(np.nanmean(self.delta_e94)),
            f"median_delta_e94_{what}": float(np.nanmedian(self.delta_e94)),
            f"p95_delta_e94_{what}": float(np.nanpercentile(self.delta_e94, 95)),
            "per_texel_relative_error_pct": float(np.nanmean(self.texel_relative_pct)),
            "per_texel_delta_e94": float(np.nanmean(self.texel_delta_e94)),
            "max_corner_error_px": float(self.corner_error_px.max()),
            "mean_corner_error_px": float(self.corner_error_px.mean()),
            "max_shift_texels": float(self.shift_texels.max()),
            "mean_shift_texels": float(self.shift_texels.mean()),
            "per_camera": {
                str(camera): {
                    f"mean_relative_error_{what}_pct": float(
                        np.nanmean(self.relative_pct[self.cameras == camera])
                    ),
                    f"mean_delta_e94_{what}": float(
                        np.nanmean(self.delta_e94[self.cameras == camera])
                    ),
                }
                for camera in dict.fromkeys(self.cameras.tolist())
            },
        }


def _nominal_corners(
    capture: CaptureStore, dome_pairs: Sequence[tuple[int, int, str]], pairs: np.ndarray
) -> np.ndarray:
    """The sample square's corners on the plate as the nominal cameras project them (+0.5)."""
    rig = dome_rig(capture, "dome-run")
    geometry = rig.geometry
    half = float(recorded(rig.sample_size_m, f"{capture.path}: rig.sample_size_m")) / 2
    square = np.array([[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]])
    corners = []
    for pair in pairs:
        view, _, camera = dome_pairs[pair]
        nominal = CameraGeometry.nominal(geometry.cameras[camera])
        world = square @ stage_rotation(geometry.stage_angles_deg[view]).T
        corners.append(nominal.project(world) + 0.5)
    return np.array(corners)


def _capture(btf_path: Path, found: BTFAttrs) -> CaptureStore:
    source = found.source_capture
    if not source or found.dome_pairs is None:
        raise InputError(
            f"{btf_path}: not processed from a dome run (no source capture or dome pairs)"
        )
    try:
        return CaptureStore.open(source)
    except InputError as error:
        raise InputError(
            f"{btf_path}: the capture store it was processed from is needed: {error}"
        ) from None


def chart_field_errors(
    material, view_dirs, measured, truth, grid, interior
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per pair ``(n_pairs, n_diffuse_fields)`` the diffuse fields' mean-spectrum errors (Eq.
    6.8, Delta E94; NaN for a field whose interior the view's parallax moves off the texture)
    and ``(n_pairs,)`` the per-texel means inside them."""
    relative, colour, texel_relative, texel_colour = [], [], [], []
    for view, estimate, reference in zip(view_dirs, measured, truth, strict=True):
        fields = field_masks(material, view, estimate.shape[0], interior=interior)
        masks = fields.masks[~fields.glossy]
        seen = masks.any(axis=(1, 2))
        shown = np.flatnonzero(~fields.glossy)[seen]
        means, true_means = fields.means(estimate, shown), fields.means(reference, shown)
        relative.append(np.full(seen.size, np.nan))
        colour.append(np.full(seen.size, np.nan))
        relative[-1][seen] = relative_error(means, true_means)
        colour[-1][seen] = delta_e94(means, true_means, grid)
        inside = masks.any(axis=0)
        texel_relative.append(relative_error(estimate[inside], reference[inside]).mean())
        texel_colour.append(delta_e94(estimate[inside], reference[inside], grid).mean())
    return (
        np.array(relative),
        np.array(colour),
        np.array(texel_relative),
        np.array(texel_colour),
    )


def evaluate_dome(
    btf_path: str | Path,
    *,
    spp: int = 64,
    pairs: Sequence[int] | None = None,
    interior: float = 0.6,
) -> DomeEvaluation:
    """Compare a BTF store processed from a dome run with the twin's truth (module docstring).

    Parameters
    ----------
    btf_path
        The BTF store (``spectwin process`` of a ``dome-run`` capture).
    spp
        Samples per pixel of the truth's renders.
    pairs
        The pairs to compare (default: all; a material without chart fields leaves out those
        near the mirror configuration).
    interior
        Fraction of a chart field's width compared (its edges blur with the registration).
    """
    if isinstance(spp, bool) or not isinstance(spp, int | np.integer) or spp < 1:
        raise InputError(f"spp: expected a positive number of samples, got {spp!r}")
    btf_path = Path(btf_path)
    btf = BTFStore.open(btf_path)
    found = btf.metadata
    capture = _capture(btf_path, found)
    dome_pairs = recorded(found.dome_pairs, f"{btf.path}: dome_pairs")
    chosen = np.arange(btf.n_pairs) if pairs is None else np.asarray(pairs, int)
    if chosen.size == 0 or chosen.min() < 0 or chosen.max() >= btf.n_pairs:
        raise InputError(f"pairs: expected indices in 0..{btf.n_pairs - 1}")
    material = load_material(btf.material)
    chart = any(part.name.startswith("field_") for part in material.parts)
    if not chart:
        half = btf.light_dirs[chosen] + btf.view_dirs[chosen]
        cosine = half[:, 2] / np.linalg.norm(half, axis=1)
        chosen = chosen[cosine < np.cos(np.radians(SPECULAR_DEG))]
    lights, views, texels = btf.light_dirs[chosen], btf.view_dirs[chosen], btf.texels[0]
    on_holder = replace(material, parts=(*holder_parts(), *material.parts))
    truth = np.pi * truth_btf(
        on_holder,
        lights,
        views,
        texels=texels,
        passbands=spectral_passbands(btf.grid.wavelengths_nm),
        spp=spp,
    ).astype(np.float64)
    measured = np.pi * np.stack([btf.read_pair(int(pair)) for pair in chosen]).astype(np.float64)
    if chart:
        errors = chart_field_errors(material, views, measured, truth, btf.grid, interior)
    else:
        span = FINE_GRID.stop_nm - FINE_GRID.start_nm
        grey = SampledSpectra(FINE_GRID, np.full((1, FINE_GRID.size), 1 / span))
        alone = np.pi * truth_btf(material, lights, views, texels=texels, passbands=grey, spp=16)
        shows = alone[..., 0] >= MATERIAL_TEXEL_REFLECTANCE
        errors = texel_errors(measured, truth, btf.grid, shows)
    shifts = [
        float(
            np.linalg.norm(phase_cross_correlation(t.mean(-1), m.mean(-1), upsample_factor=20)[0])
        )
        for t, m in zip(truth, measured, strict=True)
    ]
    corners = btf.corners_xy()[chosen]
    return DomeEvaluation(
        btf.material,
        chart,
        chosen,
        np.array([dome_pairs[pair][2] for pair in chosen]),
        *errors,
        np.linalg.norm(corners - _nominal_corners(capture, dome_pairs, chosen), axis=2),
        np.array(shifts),
        measured,
        truth,
        btf.grid,
    )


def write_dome_figure(evaluation: DomeEvaluation, path: str | Path) -> Path:
    """Six panels: the error histograms (Eq. 6.8, Delta E94), the mean errors per RGB camera,
    measured against true spectra of the pair with the median error, and that pair's measured
    and true textures (sRGB previews under equal energy)."""
    path = Path(path)
    figure = Figure(figsize=(16, 9))
    axes = figure.subplots(2, 3)
    what = "diffuse field" if evaluation.chart else "material texel"
    for axis, values, label in (
        (axes[0, 0], evaluation.relative_pct, "relative error (Eq. 6.8), %"),
        (axes[0, 1], evaluation.delta_e94, "Delta E94 (ten CIE illuminants)"),
    ):
        finite = values[np.isfinite(values)]
        axis.hist(finite, bins=np.linspace(0, np.percentile(finite, 99), 40), color="tab:blue")
        axis.axvline(finite.mean(), color="k", linewidth=1)
        axis.set(
            xlabel=f"{label}; 99 % of them shown",
            ylabel=f"{what} x pair count",
            title=f"{evaluation.material}: mean {finite.mean():.2f}, median "
            f"{np.median(finite):.2f}",
        )
    cameras = list(dict.fromkeys(evaluation.cameras.tolist()))
    means = [np.nanmean(evaluation.relative_pct[evaluation.cameras == c]) for c in cameras]
    axes[0, 2].bar(cameras, means, color="tab:blue")
    axes[0, 2].set(ylabel="mean relative error (Eq. 6.8), %", title="per RGB camera")
    per_pair = np.nanmean(evaluation.relative_pct, axis=1)
    median = int(np.argsort(per_pair)[per_pair.size // 2])
    measured, truth = evaluation.measured[median], evaluation.truth[median]
    rows = np.linspace(0, measured.shape[0] - 1, 4).astype(int)[1:-1]
    for row in rows:
        for column in rows:
            wavelengths = evaluation.grid.wavelengths_nm
            (line,) = axes[1, 0].plot(wavelengths, truth[row, column])
            axes[1, 0].plot(wavelengths, measured[row, column], "o", color=line.get_color())
    pair = evaluation.pairs[median]
    axes[1, 0].set(
        xlabel="wavelength, nm",
        ylabel="reflectance factor",
        title=f"pair {pair}: lines truth, dots measured (4 texels)",
    )
    for axis, image, name in ((axes[1, 1], measured, "measured"), (axes[1, 2], truth, "truth")):
        axis.imshow(spectral_to_srgb(image, evaluation.grid))
        axis.set_title(f"pair {pair} ({evaluation.cameras[median]}): {name}", fontsize=9)
        axis.axis("off")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    return path
