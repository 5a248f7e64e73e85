"""A specular lobe fitted per texel of a measured BTF, so that rendering can hold highlights
that the direction sampling only touches (thesis 4.2, Figure 4.6 on glossy materials).

A glossy surface's highlight is narrower than the spacing of a measured direction set (a GGX
roughness of 0.08 is a lobe a few degrees wide; the twin's reduced sampling is 30 degrees apart),
so interpolating the measured pairs smears the few mirror-configuration values over whole
triangles of directions, and a glossy field renders as a white patch. Here each texel's BTF is
split into an analytic lobe and a measured residual:

.. math::

    R(l, v, \\lambda) = k f_\\alpha(l, v) + \\bigl(R(l, v, \\lambda) - k f_\\alpha(l, v)\\bigr)

with :math:`f_\\alpha` the Cook-Torrance specular term of a dielectric coating (index 1.5,
spectrally flat) with GGX or Beckmann microfacets of roughness :math:`\\alpha`:
:math:`f_\\alpha = F(l \\cdot h) D_\\alpha(h) G_\\alpha(l, v) / (4 \\cos\\theta_l \\cos\\theta_v)`,
Smith's separable shadowing. The renderer evaluates the lobe at any direction and interpolates
only the residual, which is smooth wherever the lobe model holds. At the measured pairs the sum
is the measurement exactly.

The fit, per texel, on the band mean :math:`m_p` of the pairs :math:`p` (the lobe is flat, the
diffuse part nearly constant over directions), robust to pairs where the relief's parallax or
shadows hide the highlight from the texel: for each roughness of a grid and both distributions,
the weight :math:`k \\ge 0` is the upper quartile of :math:`(m_p - \\tilde m) / f_\\alpha` over
the pairs in the lobe's core (:data:`PEAK_FRACTION`; :math:`\\tilde m` the median over all
pairs) and the fit's error the sum of :math:`m_p - \\tilde m - k f_\\alpha` where positive
plus :data:`HIDDEN_COST` times its magnitude where negative (a hidden peak costs little, a
missed one fully). Where the pairs miss the lobe's flanks only its peak is measured, which fixes
:math:`k / \\alpha^2` alone; of the fits that tie (:data:`TIED_ERROR`) the one with the weight
nearest a plain coating's, :math:`k = 1`, is taken. A texel keeps its lobe only where enough
core pairs agree with its weight (:data:`MIN_AGREEING`), its peak stands out of the diffuse
level (:data:`MIN_PEAK`), the lobe removes at least :data:`MIN_GAIN` of the texel's error and
the texel varies more than noise (:data:`MIN_VARIATION`). A texel left without a lobe takes the
nearest texel's lobe within :data:`SHARE_RADIUS` texels if one of that lobe's core pairs agrees
with its own measurement (the edges of a raised glossy field, whose peaks the relief hides from
most pairs); elsewhere :math:`k = 0` and the BTF renders as before.

References
----------
- Walter, B., Marschner, S. R., Li, H., Torrance, K. E. (2007). Microfacet Models for
  Refraction through Rough Surfaces. EGSR (GGX and Beckmann distributions, Smith shadowing and
  its rational approximation for Beckmann).
- Cook, R. L., Torrance, K. E. (1982). A Reflectance Model for Computer Graphics. ACM TOG 1(1).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from recon.errors import InputError

__all__ = [
    "COATING_IOR",
    "AGREEMENT",
    "HIDDEN_COST",
    "MIN_AGREEING",
    "MIN_GAIN",
    "MIN_PEAK",
    "MIN_VARIATION",
    "PEAK_FRACTION",
    "ROUGHNESS_GRID",
    "SHARE_RADIUS",
    "TIED_ERROR",
    "SpecularLobes",
    "dielectric_fresnel",
    "fit_specular_lobes",
    "microfacet_specular",
]

COATING_IOR = 1.5
"""Refractive index of the coating whose Fresnel reflectance the lobe carries."""

ROUGHNESS_GRID = np.geomspace(0.01, 0.3, 51)
"""Roughnesses the fit tries. Broader lobes (tens of degrees wide) are resolved by the measured
directions themselves and interpolate without an analytic lobe."""

TIED_ERROR = 0.02
"""Fits whose residual is within this fraction of the best are equally good (see the fit)."""

HIDDEN_COST = 0.1
"""Cost of a pair measured below the lobe, relative to one above: the relief's parallax and
shadows hide a highlight from some pairs but never add one, so a lobe that misses a measured
peak is worse than one that overshoots where the peak was hidden."""

MIN_GAIN = 0.5
"""Fraction of the texel's error without a lobe that its lobe must remove."""

SHARE_RADIUS = 1.5
"""Distance in texels within which a lobe-less texel looks for a neighbour's lobe (see the fit):
its eight neighbours. Farther, the matte texels bordering a raised glossy field, which see its
highlight through the parallax at a few pairs only, would take lobes too."""

PEAK_FRACTION = 0.25
"""Pairs whose half vector sees at least this fraction of a candidate lobe's peak microfacet
density fix its weight."""

AGREEMENT = 0.25
"""Relative difference within which a core pair's ratio agrees with the fitted weight."""

MIN_AGREEING = 3
"""Core pairs that must agree with a texel's fitted weight for it to keep the lobe (the relief's
parallax may hide the highlight at the others)."""

MIN_PEAK = 0.5
"""The kept lobe's peak must be at least this multiple of the texel's median band mean."""

MIN_VARIATION = 0.05
"""Mean absolute deviation from the median over the pairs, relative to the texel's mean, below
which a texel is taken as matte (its variation is noise or shading)."""


def dielectric_fresnel(cos_theta: np.ndarray, ior: float = COATING_IOR) -> np.ndarray:
    """Unpolarized Fresnel reflectance of light arriving from outside a dielectric of index
    ``ior`` at ``cos_theta`` to the (micro)surface normal."""
    cos_i = np.clip(cos_theta, 0.0, 1.0)
    sin_t_squared = (1 - cos_i**2) / ior**2
    cos_t = np.sqrt(np.maximum(1 - sin_t_squared, 0.0))
    parallel = (ior * cos_i - cos_t) / (ior * cos_i + cos_t)
    perpendicular = (cos_i - ior * cos_t) / (cos_i + ior * cos_t)
    return 0.5 * (parallel**2 + perpendicular**2)


def _distribution_and_shadowing(
    cos_h: np.ndarray, cos_l: np.ndarray, cos_v: np.ndarray, alpha: np.ndarray, beckmann: np.ndarray
) -> tuple[np.ndarray, np.ndarray | float]:
    """Microfacet density at the half vector and Smith's shadowing of both directions, for GGX
    or (where ``beckmann``) Beckmann microfacets with the rational shadowing of Walter et al."""
    alpha_squared = alpha**2
    tan_h_squared = (1 - cos_h**2) / cos_h**2
    ggx = alpha_squared / (np.pi * cos_h**4 * (alpha_squared + tan_h_squared) ** 2)
    gauss = np.exp(-tan_h_squared / alpha_squared) / (np.pi * alpha_squared * cos_h**4)
    shadowing: np.ndarray | float = 1.0
    for cos_w in (cos_l, cos_v):
        tan_w = np.sqrt(np.maximum(1 - cos_w**2, 0.0)) / np.maximum(cos_w, 1e-9)
        smith_ggx = 2 / (1 + np.sqrt(1 + alpha_squared * tan_w**2))
        a = 1 / np.maximum(alpha * tan_w, 1e-12)
        smith_beckmann = np.where(
            a >= 1.6, 1.0, (3.535 * a + 2.181 * a**2) / (1 + 2.276 * a + 2.577 * a**2)
        )
        shadowing = shadowing * np.where(beckmann, smith_beckmann, smith_ggx)
    return np.where(beckmann, gauss, ggx), shadowing


def microfacet_specular(
    light: np.ndarray,
    view: np.ndarray,
    alpha: np.ndarray | float,
    beckmann: np.ndarray | bool = False,
) -> np.ndarray:
    """The specular term :math:`f_\\alpha(l, v)` in 1/sr (module docstring) for unit directions
    ``(..., 3)`` in the sample frame (z the normal), roughness ``alpha`` and the microfacet
    distribution (GGX, or Beckmann where ``beckmann``), all broadcast."""
    cos_l, cos_v = light[..., 2], view[..., 2]
    half = light + view
    half = half / np.linalg.norm(half, axis=-1, keepdims=True)
    cos_h = np.clip(half[..., 2], 1e-9, 1.0)
    distribution, shadowing = _distribution_and_shadowing(
        cos_h, cos_l, cos_v, np.asarray(alpha, np.float64), np.asarray(beckmann, bool)
    )
    fresnel = dielectric_fresnel(np.einsum("...i,...i->...", light, half))
    value = fresnel * distribution * shadowing / (4 * cos_l * cos_v)
    return np.where((cos_l > 0) & (cos_v > 0), value, 0.0)


@dataclass(frozen=True)
class SpecularLobes:
    """Per texel the fitted lobe: ``roughness``, ``weight`` (0: none) and whether its
    microfacets are ``beckmann`` (else GGX), each ``(H, W)``."""

    roughness: np.ndarray
    weight: np.ndarray
    beckmann: np.ndarray

    @property
    def glossy_fraction(self) -> float:
        """Fraction of the texels that carry a lobe."""
        return float((self.weight > 0).mean())

    def residual(self, light: np.ndarray, view: np.ndarray, reflectance: np.ndarray) -> np.ndarray:
        """What the lobes leave of a BTF ``(n, H, W, K)`` measured at ``light``, ``view``: each
        pair less its lobe, but never below the smaller of its value and the texel's median
        band mean over the pairs, so that a pair where the relief's parallax hid the highlight
        does not become a hole in the interpolated residual."""
        means = reflectance.mean(axis=-1, dtype=np.float64)
        base = np.median(means, axis=0)
        lobe = np.clip(self.values(light, view), 0.0, np.maximum(means - base, 0.0))
        return (reflectance - lobe[..., None]).astype(reflectance.dtype)

    def values(self, light: np.ndarray, view: np.ndarray) -> np.ndarray:
        """The lobes ``(n, H, W)`` at the pairs ``light``, ``view`` ``(n, 3)``."""
        shape = (-1, 1, 1, 3)
        lobe = microfacet_specular(
            light.reshape(shape), view.reshape(shape), self.roughness[None], self.beckmann[None]
        )
        return self.weight[None] * lobe


def _asymmetric_error(difference: np.ndarray) -> np.ndarray:
    """Per texel the fit's error of ``difference`` = measured less modelled ``(P, T)``: pairs
    measured below the model cost :data:`HIDDEN_COST` of those above."""
    return np.maximum(difference, 0.0).sum(axis=0) + HIDDEN_COST * np.maximum(-difference, 0.0).sum(
        axis=0
    )


def fit_specular_lobes(
    light_dirs: np.ndarray, view_dirs: np.ndarray, reflectance: np.ndarray
) -> SpecularLobes:
    """Fit a lobe per texel to a BTF (module docstring).

    Parameters
    ----------
    light_dirs, view_dirs
        ``(n_pairs, 3)`` unit directions of the pairs.
    reflectance
        ``(n_pairs, H, W, K)`` the BTF in 1/sr.
    """
    reflectance = np.asarray(reflectance)
    if reflectance.ndim != 4 or not reflectance.shape[0] == len(light_dirs) == len(view_dirs):
        raise InputError(
            f"reflectance: expected (n_pairs, H, W, K) for {len(light_dirs)} pairs, got "
            f"{reflectance.shape}"
        )
    n_pairs, height, width, _ = reflectance.shape
    means = reflectance.mean(axis=-1, dtype=np.float64).reshape(n_pairs, -1)  # (P, T)
    base = np.median(means, axis=0)
    excess = means - base
    without = np.abs(excess).sum(axis=0)
    errors, weights, agreeing, peak_values, used = [], [], [], [], []
    half = light_dirs + view_dirs
    cos_h = half[:, 2] / np.linalg.norm(half, axis=1)
    tan_h_squared = (1 - cos_h**2) / np.maximum(cos_h, 1e-9) ** 2
    for alpha, beckmann in itertools.product(ROUGHNESS_GRID, (False, True)):
        lobe = microfacet_specular(light_dirs, view_dirs, alpha, beckmann)
        core = (
            np.exp(-tan_h_squared / alpha**2)
            if beckmann
            else 1 / (1 + tan_h_squared / alpha**2) ** 2
        )  # the microfacet density relative to its peak
        peaks = (core >= PEAK_FRACTION) & (lobe > 0)
        if not peaks.any():
            continue
        ratios = excess[peaks] / lobe[peaks, None]
        weight = np.maximum(np.percentile(ratios, 75, axis=0), 0.0)
        errors.append(_asymmetric_error(excess - np.outer(lobe, weight)))
        weights.append(weight)
        agreeing.append((np.abs(ratios - weight) <= AGREEMENT * weight).sum(axis=0))
        peak_values.append(weight * lobe.max())
        used.append((alpha, beckmann))
    if not used:
        raise InputError(
            "light_dirs, view_dirs: no pair near a mirror configuration; no lobe can be fitted"
        )
    candidate_errors, candidate_weights = np.array(errors), np.array(weights)  # (n, T)
    tied = candidate_errors <= (1 + TIED_ERROR) * candidate_errors.min(axis=0) + 1e-30
    choice = np.argmin(
        np.where(tied, np.abs(np.log(np.maximum(candidate_weights, 1e-30))), np.inf), axis=0
    )
    texel = np.arange(means.shape[1])
    best_weight = candidate_weights[choice, texel]
    best_alpha = np.array([used[c][0] for c in choice])
    best_beckmann = np.array([used[c][1] for c in choice])
    level = np.abs(means.mean(axis=0))
    varies = without / n_pairs > MIN_VARIATION * level
    confirmed = np.array(agreeing)[choice, texel] >= MIN_AGREEING
    strong = np.array(peak_values)[choice, texel] >= MIN_PEAK * np.maximum(base, 0.0)
    best_error = candidate_errors[choice, texel]
    explains = best_error <= (1 - MIN_GAIN) * _asymmetric_error(excess)
    keep = varies & confirmed & strong & explains & (best_weight > 0)
    own = SpecularLobes(
        np.where(keep, best_alpha, ROUGHNESS_GRID[0]).reshape(height, width),
        np.where(keep, best_weight, 0.0).reshape(height, width),
        (keep & best_beckmann).reshape(height, width),
    )
    return _shared_with_neighbours(
        own, light_dirs, view_dirs, excess.reshape(n_pairs, height, width)
    )


def _shared_with_neighbours(
    lobes: SpecularLobes, light_dirs: np.ndarray, view_dirs: np.ndarray, excess: np.ndarray
) -> SpecularLobes:
    """``lobes`` with every lobe-less texel given its nearest texel's lobe within
    :data:`SHARE_RADIUS` where a pair in that lobe's core agrees with the texel's ``excess``
    ``(P, H, W)`` over its median (module docstring)."""
    from scipy import ndimage

    has = lobes.weight > 0
    if not has.any() or has.all():
        return lobes
    distance, (rows, columns) = ndimage.distance_transform_edt(~has, return_indices=True)
    nearest = SpecularLobes(
        lobes.roughness[rows, columns], lobes.weight[rows, columns], lobes.beckmann[rows, columns]
    )
    model = nearest.values(light_dirs, view_dirs)
    core = model >= PEAK_FRACTION * model.max(axis=0)
    agrees = (core & (np.abs(excess - model) <= AGREEMENT * model)).any(axis=0)
    take = ~has & (distance <= SHARE_RADIUS) & agrees
    return SpecularLobes(
        np.where(take, nearest.roughness, lobes.roughness),
        np.where(take, nearest.weight, lobes.weight),
        np.where(take, nearest.beckmann, lobes.beckmann),
    )
