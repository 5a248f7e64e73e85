"""The VariSpec liquid-crystal tunable filter in front of the spectral camera (thesis 3.2.2).

Each band's transmission is a Gaussian passband of the model's full width at half maximum around
its centre wavelength, scaled by a peak transmission that falls toward short wavelengths
(Fig. 3.4f), times the loss of the entrance polarizer for unpolarized light, plus a small
out-of-band leakage floor of the liquid-crystal stack.

References
----------
- The thesis, section 3.2.2 (VariSpec VS-10, 10 nm bandwidth, models with 7, 10 and 20 nm;
  centres 400-720 nm in 10 nm steps) and Fig. 3.4f (transmission falling toward the blue).
- Gat, N. (2000). Imaging spectroscopy using tunable filters: a review. Proc. SPIE 4056.
  doi:10.1117/12.381686 (LCTF passbands, polarizer loss, out-of-band blocking).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid

__all__ = ["VARISPEC_FWHM_NM", "LiquidCrystalTunableFilter"]

VARISPEC_FWHM_NM = {"VS-07": 7.0, "VS-10": 10.0, "VS-20": 20.0}
"""Bandwidths of the three VariSpec models named in the thesis (section 3.2.2)."""


@dataclass(frozen=True)
class LiquidCrystalTunableFilter:
    """VariSpec-class LCTF.

    Parameters
    ----------
    fwhm_nm
        Passband full width at half maximum (10 nm for the VS-10).
    band_centres_nm
        Centre wavelengths of the bands the filter is tuned to.
    peak_transmission_max, peak_transmission_half_nm, peak_transmission_width_nm
        Peak transmission for polarized light,
        :math:`P(\\lambda_c) = P_{max} / (1 + e^{-(\\lambda_c - \\lambda_{1/2}) / w})`, which
        falls toward short wavelengths (Fig. 3.4f).
    polarizer_transmission
        Transmission of the entrance polarizer for unpolarized light (0.5 for an ideal one).
    leakage
        Out-of-band transmission floor of the liquid-crystal stack.
    """

    fwhm_nm: float = 10.0
    band_centres_nm: tuple[float, ...] = field(
        default_factory=lambda: tuple(DEFAULT_GRID.wavelengths_nm.tolist())
    )
    peak_transmission_max: float = 0.62
    peak_transmission_half_nm: float = 470.0
    peak_transmission_width_nm: float = 45.0
    polarizer_transmission: float = 0.5
    leakage: float = 2e-4

    def __post_init__(self) -> None:
        if not self.fwhm_nm > 0:
            raise InputError(f"fwhm_nm: expected a positive bandwidth, got {self.fwhm_nm}")
        centres = np.asarray(self.band_centres_nm, dtype=np.float64)
        if centres.ndim != 1 or centres.size == 0 or np.any(np.diff(centres) <= 0):
            raise InputError(
                "band_centres_nm: expected a non-empty, strictly increasing list of wavelengths"
            )
        for name in ("peak_transmission_max", "polarizer_transmission"):
            if not 0 < getattr(self, name) <= 1:
                raise InputError(f"{name}: expected a transmission in (0, 1]")
        if not 0 <= self.leakage < 1:
            raise InputError(f"leakage: expected a transmission in [0, 1), got {self.leakage}")

    @classmethod
    def varispec(cls, model: str = "VS-10", **overrides: Any) -> LiquidCrystalTunableFilter:
        """The VariSpec ``model`` ("VS-07", "VS-10" or "VS-20") with optional overrides."""
        if model not in VARISPEC_FWHM_NM:
            raise InputError(f"model: expected one of {sorted(VARISPEC_FWHM_NM)}, got {model!r}")
        return cls(fwhm_nm=VARISPEC_FWHM_NM[model], **overrides)

    @property
    def band_names(self) -> tuple[str, ...]:
        return tuple(f"lctf_{centre:g}nm" for centre in self.band_centres_nm)

    def peak_transmission(self) -> np.ndarray:
        """Transmission at each band centre for unpolarized light (polarizer included)."""
        centres = np.asarray(self.band_centres_nm)
        logistic = 1 / (
            1
            + np.exp(-(centres - self.peak_transmission_half_nm) / self.peak_transmission_width_nm)
        )
        return self.polarizer_transmission * self.peak_transmission_max * logistic

    def transmission(self, grid: WavelengthGrid) -> SampledSpectra:
        """Transmission of every band, values ``(n_bands, K)``, for unpolarized light.

        A 10 nm passband needs a grid of a few nm or finer for accurate band integrals.
        """
        centres = np.asarray(self.band_centres_nm)[:, None]
        passband = np.exp(-4 * np.log(2) * ((grid.wavelengths_nm - centres) / self.fwhm_nm) ** 2)
        liquid_crystal = self.peak_transmission()[:, None] / self.polarizer_transmission * passband
        values = self.polarizer_transmission * (liquid_crystal + self.leakage)
        return SampledSpectra(grid, values, self.band_names)
