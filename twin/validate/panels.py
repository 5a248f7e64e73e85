"""The three panels of a rendering validation (thesis 4.2, Figure 4.6) and their comparison.

A photograph of the sample, the BTF rendered spectrally and the BTF rendered in RGB, all three
in CIE XYZ of one camera, are compared in CIE L*a*b* relative to one white (the light's: a
perfect white diffuser facing the sample's normal), Delta E94 per pixel over a region of the
sample: the interiors of a chart's matte fields (the twin's colour checker), or the interior of
the sample's square (any other material, and every user's photograph). Where the material has
chart fields, the Delta E94 of every field's mean colour is added. The figure shows the panels
with one white balance and one tone curve, the two Delta E94 maps and their histograms.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import colour
import numpy as np

__all__ = ["Panels", "compare_panels", "lab", "polygon_mask", "write_panels"]


def lab(xyz: np.ndarray, white: np.ndarray) -> np.ndarray:
    """CIE L*a*b* of ``xyz`` ``(..., 3)`` relative to ``white`` (XYZ; Y of white = L* 100)."""
    return colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xyY(white / white[1])[:2])


@dataclass(frozen=True)
class Panels:
    """The three panels in XYZ ``(H, W, 3)``, the white, the compared region ``mask``
    ``(H, W)`` (named by ``region``), Delta E94 against the photograph per pixel, and for a
    chart the interiors of its fields ``(n_fields, H, W)`` and which of them are glossy."""

    photograph: np.ndarray
    spectral: np.ndarray
    rgb: np.ndarray
    white_xyz: np.ndarray
    mask: np.ndarray
    region: str
    delta_e_spectral: np.ndarray
    delta_e_rgb: np.ndarray
    fields: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 1), bool))
    glossy: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    def field_delta_e(self) -> tuple[np.ndarray, np.ndarray]:
        """Delta E94 of every field's mean colour (interior), spectral and RGB rendering."""
        return (
            self.field_delta_e_between(self.spectral, self.photograph),
            self.field_delta_e_between(self.rgb, self.photograph),
        )

    def field_delta_e_between(self, image: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """``(n_fields,)`` Delta E94 of every field's mean colour (interior) in ``image`` against
        ``reference``, both XYZ ``(H, W, 3)`` of this comparison's camera, relative to its
        white."""
        image_means, reference_means = (
            np.array([values[interior].mean(axis=0) for interior in self.fields])
            for values in (image, reference)
        )
        return colour.delta_E(
            lab(image_means, self.white_xyz),
            lab(reference_means, self.white_xyz),
            method="CIE 1994",
        )

    def summary(self) -> dict[str, float]:
        """Per-pixel Delta E94 over the region (mean, median, 95th percentile) of both
        renderings and their ratio; for a chart also the field means' (matte, glossy)."""
        spectral, rgb = self.delta_e_spectral[self.mask], self.delta_e_rgb[self.mask]
        out: dict[str, float] = {}
        if len(self.fields):
            field_spectral, field_rgb = self.field_delta_e()
            matte = ~self.glossy
            out |= {
                "field_mean_delta_e94_spectral": float(field_spectral[matte].mean()),
                "field_mean_delta_e94_rgb": float(field_rgb[matte].mean()),
                "field_ratio_rgb_over_spectral": float(
                    field_rgb[matte].mean() / field_spectral[matte].mean()
                ),
                "field_mean_delta_e94_spectral_glossy": float(field_spectral[~matte].mean()),
                "field_mean_delta_e94_rgb_glossy": float(field_rgb[~matte].mean()),
            }
        return out | {
            "mean_delta_e94_spectral": float(spectral.mean()),
            "mean_delta_e94_rgb": float(rgb.mean()),
            "ratio_rgb_over_spectral": float(rgb.mean() / spectral.mean()),
            "median_delta_e94_spectral": float(np.median(spectral)),
            "median_delta_e94_rgb": float(np.median(rgb)),
            "p95_delta_e94_spectral": float(np.percentile(spectral, 95)),
            "p95_delta_e94_rgb": float(np.percentile(rgb, 95)),
            "compared_pixels": int(self.mask.sum()),
        }


def compare_panels(
    photograph: np.ndarray,
    spectral: np.ndarray,
    rgb: np.ndarray,
    white_xyz: np.ndarray,
    mask: np.ndarray,
    region: str,
    *,
    fields: np.ndarray | None = None,
    glossy: np.ndarray | None = None,
) -> Panels:
    """The comparison of three XYZ panels ``(H, W, 3)`` over ``mask`` (module docstring).

    Parameters
    ----------
    photograph, spectral, rgb
        The photograph and the two renderings, XYZ of one camera.
    white_xyz
        The white they are seen relative to.
    mask
        ``(H, W)`` the compared pixels.
    region
        What ``mask`` covers, in words (figure titles).
    fields, glossy
        A chart's field interiors ``(n, H, W)`` and which fields are glossy, or ``None``.

    Returns
    -------
    Panels
    """
    reference = lab(photograph, white_xyz)
    extra = {} if fields is None else {"fields": fields, "glossy": np.asarray(glossy, bool)}
    return Panels(
        photograph,
        spectral,
        rgb,
        white_xyz,
        mask,
        region,
        colour.delta_E(lab(spectral, white_xyz), reference, method="CIE 1994"),
        colour.delta_E(lab(rgb, white_xyz), reference, method="CIE 1994"),
        **extra,
    )


def polygon_mask(corners_px: np.ndarray, width: int, height: int) -> np.ndarray:
    """``(height, width)`` the pixels whose centres lie inside the polygon ``corners_px``
    ``(n, 2)`` (column, row; pixel centres at +0.5)."""
    from matplotlib.path import Path as Polygon

    column, row = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    centres = np.column_stack([column.ravel(), row.ravel()])
    return Polygon(corners_px).contains_points(centres).reshape(height, width)


def _display(xyz: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    """sRGB for display: white balanced to D65 (CAT02), one tone curve for all panels."""
    adapted = colour.chromatic_adaptation(
        xyz / white_xyz[1],
        white_xyz / white_xyz[1],
        colour.xy_to_XYZ([0.3127, 0.3290]),
        method="Von Kries",
        transform="CAT02",
    )
    return np.clip(colour.XYZ_to_sRGB(adapted * 1.6, apply_cctf_encoding=True), 0, 1)


def write_panels(panels: Panels, path: str | Path) -> Path:
    """The three panels, the two Delta E94 maps over the compared region and their histograms,
    as a PNG at ``path``."""
    from matplotlib.figure import Figure

    path = Path(path)
    plot = Figure(figsize=(24, 4.5))
    axes = plot.subplots(1, 6)
    titles = ("(a) photograph", "(b) spectral rendering", "(c) RGB rendering")
    for axis, xyz, title in zip(
        axes[:3], (panels.photograph, panels.spectral, panels.rgb), titles, strict=True
    ):
        axis.imshow(_display(xyz, panels.white_xyz))
        axis.set_title(title)
        axis.axis("off")
    limit = float(np.percentile(panels.delta_e_rgb[panels.mask], 99))
    summary = panels.summary()
    for axis, values, name in (
        (axes[3], panels.delta_e_spectral, "spectral"),
        (axes[4], panels.delta_e_rgb, "rgb"),
    ):
        shown = axis.imshow(np.where(panels.mask, values, np.nan), vmin=0, vmax=limit)
        fields = summary.get(f"field_mean_delta_e94_{name}")
        axis.set_title(
            f"Delta E94 {name}, {panels.region}: pixels {summary[f'mean_delta_e94_{name}']:.2f}"
            + ("" if fields is None else f", field means {fields:.2f}"),
            fontsize=9,
        )
        axis.axis("off")
        plot.colorbar(shown, ax=axis, fraction=0.046)
    bins = np.linspace(0, max(limit, 1e-6), 40)
    for values, name in ((panels.delta_e_spectral, "spectral"), (panels.delta_e_rgb, "RGB")):
        axes[5].hist(values[panels.mask], bins=bins, histtype="step", label=name)
    axes[5].set_xlabel("Delta E94")
    axes[5].set_ylabel("pixels")
    axes[5].set_title(f"Delta E94 over the {panels.region}", fontsize=9)
    axes[5].legend()
    plot.tight_layout()
    plot.savefig(path, dpi=100)
    return path
