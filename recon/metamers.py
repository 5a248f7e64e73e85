"""Design of metamers: reflectances that a given camera cannot tell apart under a given light.

A camera with response :math:`R_{cam}` (K x 3) under illuminant :math:`E` sees
:math:`c = \\sum_\\lambda w_\\lambda R_{cam}(\\lambda) E(\\lambda) \\rho(\\lambda)`: a linear map of
rank 3. Adding a "metameric black" from its null space changes the spectrum but not the camera
signal (thesis 2.1 and chapter 6: the ambiguity spectralization must resolve). Smooth metameric
blacks are made by projecting smooth random bumps onto the null space.

References
----------
- Wyszecki, G., & Stiles, W. S. (1982). Color Science, 2nd ed., section 3.8 (metameric blacks).
"""

from __future__ import annotations

import numpy as np
from scipy import linalg

from recon.errors import InputError
from recon.metrics import relative_error
from recon.spectra import SampledSpectra

__all__ = ["camera_signal", "design_metamer"]


def camera_signal(
    reflectance: SampledSpectra, response: SampledSpectra, illuminant: SampledSpectra
) -> np.ndarray:
    """Camera values :math:`\\int \\rho E R_c d\\lambda` per channel, ``(..., n_channels)``."""
    for name, spectra in (("response", response), ("illuminant", illuminant)):
        if spectra.grid != reflectance.grid:
            raise InputError(f"{name}: expected the reflectance's grid")
    weights = reflectance.grid.quadrature_weights() * illuminant.values
    return (reflectance.values * weights) @ response.values.T


def design_metamer(
    reflectance: SampledSpectra,
    response: SampledSpectra,
    illuminant: SampledSpectra,
    rng: np.random.Generator,
    *,
    relative_difference_percent: float = 20.0,
    bounds: tuple[float, float] = (0.02, 0.95),
    bump_width_nm: float = 40.0,
    attempts: int = 400,
) -> SampledSpectra:
    """A smooth reflectance with the same camera signal and a different spectrum.

    Parameters
    ----------
    reflectance
        The spectrum to match (1-D, within ``bounds``).
    response, illuminant
        The camera's channel responses ``(n, K)`` and the light ``(K,)``, on the same grid.
    rng
        Source of the random smooth directions.
    relative_difference_percent
        Wanted relative error (Eq. 6.8) between the two spectra.
    bounds
        Range the metamer's values must stay in.
    bump_width_nm
        Width of the Gaussian bumps the metameric black is made of (smoothness).
    attempts
        Random directions tried; the one reaching the target with most headroom wins.
    """
    if not isinstance(rng, np.random.Generator):
        raise InputError("rng: expected a numpy.random.Generator")
    low, high = bounds
    base = reflectance.values
    if base.ndim != 1 or np.any(base < low) or np.any(base > high):
        raise InputError(f"reflectance: expected one spectrum within bounds {bounds}")
    weights = reflectance.grid.quadrature_weights() * illuminant.values
    null = linalg.null_space(response.values * weights)
    wavelengths = reflectance.wavelengths_nm
    best, best_headroom = None, 0.0
    for _ in range(attempts):
        centres = rng.uniform(wavelengths[0], wavelengths[-1], 4)
        bumps = rng.standard_normal(4) @ np.exp(
            -0.5 * ((wavelengths[None, :] - centres[:, None]) / bump_width_nm) ** 2
        )
        black = null @ (null.T @ bumps)
        with np.errstate(divide="ignore"):
            up = np.where(black > 0, (high - base) / black, np.inf)
            down = np.where(black < 0, (low - base) / black, np.inf)
        largest_step = float(min(up.min(), down.min()))
        reached = float(relative_error(base + largest_step * black, base))
        if reached < relative_difference_percent:
            continue
        headroom = reached / relative_difference_percent
        if headroom > best_headroom:
            step = largest_step * relative_difference_percent / reached
            best, best_headroom = base + step * black, headroom
    if best is None:
        raise InputError(
            f"design_metamer: no smooth metamer {relative_difference_percent:g} % away within "
            f"bounds {bounds} after {attempts} attempts"
        )
    return SampledSpectra(reflectance.grid, best)
