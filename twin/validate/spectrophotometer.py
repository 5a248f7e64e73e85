"""The spectrophotometer comparison of thesis 4.2 (Figures 4.3, 4.4): a 45/0 instrument on the
true material versus the same geometry integrated from a measured BTF.

A 45/0 annular instrument lights its spot from all azimuths at 45 degrees and looks straight
down; relative to a perfect white diffuser in the same geometry it reports the reflectance
factor :math:`R(\\lambda) = \\pi \\bar f_r(45^\\circ \\to 0^\\circ)`, the BRDF averaged over the
annulus. The instrument is simulated on the twin's true material
(:func:`twin.render.truth.truth_btf`
with ``azimuths`` lights on the 45 degree ring and the top view, averaged), and the BTF is
integrated over the same ring by interpolating between its measured directions
(:func:`twin.render.plugins.btf_bsdf.interpolate_table`); both are averaged over a circular spot in
the middle
of every chart field. The instrument's spectra are resolved to the BTF's bands with the
gonioreflectometer's band weighting (:func:`twin.sensor.band_weights.instrument_passbands`; a
dome BTF's with the dome's spectral camera's), as a
finely sampling laboratory spectrophotometer's readings would be before comparing them with the
camera's bands, so that the comparison measures geometry and calibration, not band shapes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recon.btf.store import BTFStore
from recon.metrics import relative_error
from recon.spectra import SampledSpectra
from twin.materials import Material
from twin.render.plugins.btf_bsdf import BTFTable, CompressedTable, interpolate_table, written_table
from twin.render.truth import truth_btf
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig
from twin.sensor.band_weights import instrument_passbands

__all__ = ["FortyFiveZero", "compare_45_0", "field_spots", "write_45_0_figure"]


def field_spots(material: Material, texels: int, *, spot_fraction: float = 0.6) -> np.ndarray:
    """``(n_fields, H, W)`` circular spots of diameter ``spot_fraction`` of each field's width,
    centred on the field's top face seen from straight above."""
    size = material.size_m
    centres = (np.arange(texels) + 0.5) / texels * size - size / 2
    x, y = np.meshgrid(centres, -centres)
    spots = []
    for part in (p for p in material.parts if p.name.startswith("field_")):
        low, high = part.mesh.bounds
        middle = (low[:2] + high[:2]) / 2
        radius = spot_fraction * (high[0] - low[0]) / 2
        spots.append(np.hypot(x - middle[0], y - middle[1]) < radius)
    return np.stack(spots)


@dataclass(frozen=True)
class FortyFiveZero:
    """Reflectance factors ``(n_fields, K)`` of the instrument and the BTF, and Eq. 6.8 per
    field (%)."""

    field_names: tuple[str, ...]
    glossy: np.ndarray
    instrument: np.ndarray
    btf: np.ndarray
    error_pct: np.ndarray

    def summary(self) -> dict[str, object]:
        return {
            "mean_error_matte_fields_pct": float(self.error_pct[~self.glossy].mean()),
            "max_error_matte_fields_pct": float(self.error_pct[~self.glossy].max()),
            "mean_error_glossy_fields_pct": float(self.error_pct[self.glossy].mean()),
            "per_field_pct": {
                name: round(float(error), 3)
                for name, error in zip(self.field_names, self.error_pct, strict=True)
            },
        }


def compare_45_0(
    btf: BTFStore | BTFTable | CompressedTable,
    material: Material,
    *,
    azimuths: int = 8,
    spp: int = 64,
    passbands: SampledSpectra | None = None,
) -> FortyFiveZero:
    """45/0 reflectance factors per field from the true material and from ``btf`` (a store's
    written pairs, or a table such as :func:`twin.render.plugins.btf_bsdf.store_table` gives);
    the instrument's spectra in ``passbands`` (the BTF's bands; default the
    gonioreflectometer's)."""
    lights = direction(np.full(azimuths, 45.0), np.arange(azimuths) * 360.0 / azimuths)
    top = np.array([0.0, 0.0, 1.0])
    table = written_table(btf) if isinstance(btf, BTFStore) else btf
    texels = table.texture(0, 0).shape[0]
    truth = truth_btf(
        material,
        lights,
        np.tile(top, (azimuths, 1)),
        texels=texels,
        passbands=instrument_passbands(load_rig("gonio")) if passbands is None else passbands,
        spp=spp,
    ).mean(axis=0)
    measured = np.mean([interpolate_table(table, light, top) for light in lights], axis=0)
    spots = field_spots(material, texels)
    instrument = np.pi * np.array([truth[spot].mean(axis=0) for spot in spots])
    from_btf = np.pi * np.array([measured[spot].mean(axis=0) for spot in spots])
    parts = [p for p in material.parts if p.name.startswith("field_")]
    return FortyFiveZero(
        tuple(p.name for p in parts),
        np.array([p.roughness is not None for p in parts]),
        instrument,
        from_btf,
        relative_error(from_btf, instrument),
    )


def write_45_0_figure(result: FortyFiveZero, wavelengths_nm: np.ndarray, path) -> None:
    """One panel per field: the instrument's and the BTF's reflectance factors (Fig. 4.3/4.4)."""
    from matplotlib.figure import Figure

    count = len(result.field_names)
    columns = int(np.ceil(np.sqrt(count)))
    rows = int(np.ceil(count / columns))
    width, height = 3.0 * columns, 2.4 * rows
    figure = Figure(figsize=(width, height))
    # Margins and gaps in inches, fixed: what tight_layout gave for tick labels of up to six
    # characters (0.0000), which took a third of the figure's time.
    left, right, bottom, top, column_gap, row_gap = 0.97, 0.15, 0.71, 0.35, 0.65, 0.43
    axes_width = (width - left - right - (columns - 1) * column_gap) / columns
    axes_height = (height - bottom - top - (rows - 1) * row_gap) / rows
    layout = {
        "left": left / width,
        "right": 1 - right / width,
        "bottom": bottom / height,
        "top": 1 - top / height,
        "wspace": column_gap / axes_width,
        "hspace": row_gap / axes_height,
    }
    axes = figure.subplots(rows, columns, sharex=True, gridspec_kw=layout)
    for index, axis in enumerate(np.ravel(axes)):
        if index >= count:
            axis.axis("off")
            continue
        axis.plot(wavelengths_nm, result.instrument[index], "k-", label="45/0 instrument")
        axis.plot(wavelengths_nm, result.btf[index], "o", markersize=3, label="BTF")
        kind = "glossy" if result.glossy[index] else "matte"
        axis.set_title(
            f"{result.field_names[index]} ({kind}): {result.error_pct[index]:.1f} %", fontsize=9
        )
        axis.set_ylim(bottom=0)
    np.ravel(axes)[0].legend(fontsize=7)
    figure.supxlabel("wavelength, nm")
    figure.supylabel("reflectance factor")
    figure.savefig(path, dpi=100)
