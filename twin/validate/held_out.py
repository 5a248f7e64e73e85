"""A measured (virtual) BTF at directions it did not measure, against the twin's truth.

A direction sampling is judged by what a renderer makes of it: the BTF is interpolated at
held-out light x view pairs exactly as the BTF BSDF does (barycentric in the light and in the
view direction, :func:`twin.render.plugins.btf_bsdf.interpolate_table`) and compared, per chart
field, with the true BTF rendered at those pairs (:func:`twin.render.truth.truth_btf`). Sparse
samplings lose the glossy fields' highlights between their directions; the matte fields show
noise, calibration and the filter's band averaging.

The truth's bands average the reflectance with ``passbands``; narrow passbands at the band
centres (:data:`REFERENCE_FWHM_NM`) make the filter's bandwidth part of the error, as in the
``lctf_bandwidth`` notebook (Eq. 6.8 against the reflectance at the band centre).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.metrics import delta_e94, relative_error
from recon.spectra import SampledSpectra
from twin.materials import load_material
from twin.materials.chart_fields import field_masks
from twin.render.plugins.btf_bsdf import interpolate_table, written_table
from twin.render.truth import band_passbands, truth_btf
from twin.rigs.hemisphere import direction

__all__ = ["HELD_OUT_PAIRS_DEG", "REFERENCE_FWHM_NM", "HeldOutErrors", "held_out_errors"]

HELD_OUT_PAIRS_DEG = (
    ((20.0, 0.0), (10.0, 180.0)),
    ((20.0, 0.0), (35.0, 60.0)),
    ((40.0, 120.0), (25.0, 300.0)),
    ((40.0, 120.0), (10.0, 180.0)),
    ((15.0, 240.0), (35.0, 60.0)),
    ((15.0, 240.0), (25.0, 300.0)),
)
"""Held-out (light, view) pairs as ((polar, azimuth), (polar, azimuth)) in degrees: none lies on
the rings of the built-in samplings; the first is 10 degrees from the mirror direction, where
the glossy fields' highlights are."""

REFERENCE_FWHM_NM = 1.0
"""Width of the reference passbands at the band centres: the reflectance at the centre."""


@dataclass(frozen=True)
class HeldOutErrors:
    """Per held-out pair and chart field: Eq. 6.8 (%) and Delta E94 of the field means."""

    field_names: tuple[str, ...]
    glossy: np.ndarray  # (n_fields,)
    relative_error: np.ndarray  # (n_pairs, n_fields)
    delta_e94: np.ndarray  # (n_pairs, n_fields)

    def summary(self) -> dict[str, float]:
        """Means over pairs and fields: all fields, the matte and the glossy ones."""
        matte = ~self.glossy
        return {
            "error_pct": float(self.relative_error.mean()),
            "error_matte_pct": float(self.relative_error[:, matte].mean()),
            "error_glossy_pct": float(self.relative_error[:, ~matte].mean()),
            "delta_e94": float(self.delta_e94.mean()),
            "delta_e94_matte": float(self.delta_e94[:, matte].mean()),
        }


def held_out_errors(
    btf_path: str | Path,
    *,
    pairs_deg=HELD_OUT_PAIRS_DEG,
    passbands: SampledSpectra | None = None,
    interior: float = 0.6,
    spp: int = 64,
) -> HeldOutErrors:
    """The BTF store interpolated at ``pairs_deg`` against the truth there (module docstring).

    Parameters
    ----------
    btf_path
        A BTF store of a twin material made by ``spectwin process`` (its material names the
        truth).
    pairs_deg
        ``((light_polar, light_azimuth), (view_polar, view_azimuth))`` per pair, degrees.
    passbands
        The truth's band weights (rows of unit area on ``FINE_GRID``); default Gaussians of
        :data:`REFERENCE_FWHM_NM` at the BTF's band centres.
    interior, spp
        Fraction of each field's width compared (away from its edges) and the truth's samples
        per pixel.
    """
    btf = BTFStore.open(btf_path)
    if not btf.written().any():
        raise InputError(f"{btf_path}: no direction pair is written; nothing to compare")
    material = load_material(btf.material)
    lights = np.array([direction(*light) for light, _ in pairs_deg])
    views = np.array([direction(*view) for _, view in pairs_deg])
    reference = band_passbands(btf.grid, REFERENCE_FWHM_NM) if passbands is None else passbands
    texels = btf.texels[0]
    truth = truth_btf(material, lights, views, texels=texels, passbands=reference, spp=spp)
    table = written_table(btf)
    errors, colour_errors = [], []
    for index, (light, view) in enumerate(zip(lights, views, strict=True)):
        measured = interpolate_table(table, light, view)
        fields = field_masks(material, view, texels, interior=interior)
        measured_means, truth_means = fields.means(measured), fields.means(truth[index])
        errors.append(relative_error(measured_means, truth_means))
        # Reflectance factors (BTF in 1/sr times pi) for the colour difference.
        colour_errors.append(
            delta_e94(np.pi * measured_means, np.pi * truth_means, btf.grid.wavelengths_nm)
        )
    return HeldOutErrors(fields.names, fields.glossy, np.array(errors), np.array(colour_errors))
