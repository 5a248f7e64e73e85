"""The chapter 7 experiments: spectralization against the usual methods on sparse spectral data.

Every experiment starts from a complete spectral image :math:`S` (reflectance, ``(H, W, K)``),
synthesizes camera values :math:`V = S R_{cam}` (Eq. 7.1) with Gaussian noise of a fraction of
the mean signal, hands every method the true spectra of a sparse set of pixels
(:mod:`recon.experiments.sampling`) and scores the reconstructions with the relative error of
Eq. 6.8 per pixel:

- :func:`run_protocol`: one sampling mask, all methods (sections 7.1 whisk-broom, 7.2
  push-broom, 7.6 incomplete information via :func:`recon.experiments.sampling.exclude_region`);
- :func:`spot_count_sweep`: whisk-broom with a varying number of spots (Fig. 7.9);
- :func:`noise_sweep`: RGB noise from 0.5 % to 5 % of the mean (Fig. 7.10).

The contenders are named in :data:`METHODS`; each takes a :class:`SparseInput`.

References
----------
- The thesis, chapter 7 (Eq. 7.1; sections 7.1, 7.2, 7.4, 7.5, 7.6) and Eq. 6.8.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from recon import baselines
from recon.errors import InputError
from recon.experiments.sampling import add_rgb_noise, known_spectra_from_mask, whisk_broom_mask
from recon.image_spectralization.kriging_blend import blend_with_kriging, choose_kriging_weight
from recon.metrics import relative_error
from recon.spectralize import hierarchy
from recon.spectralize.appearance_choice import choose_appearance
from recon.spectralize.prior_choice import PriorChoice, choose_prior
from recon.spectralize.solve import EnergyWeights, PointSpectra, spectralize

__all__ = [
    "METHODS",
    "ProtocolResult",
    "SparseInput",
    "noise_sweep",
    "run_protocol",
    "spot_count_sweep",
]


@dataclass(frozen=True)
class SparseInput:
    """What every method sees: noisy camera values ``rgb`` ``(H, W, C)``, the projection
    ``response`` ``(K, C)`` and the known spectra ``spectra`` ``(m, K)`` at the row-major
    ``pixels``."""

    rgb: np.ndarray
    response: np.ndarray
    pixels: np.ndarray
    spectra: np.ndarray


_SPECTRALIZATION: dict[str, Any] = {
    "appearance": "rgbxy",
    "weights": EnergyWeights(delta=0.0),
    "tol": 1e-8,
}


def _spectralization(data: SparseInput, p_dyn: float = 0.0, prior: str = "spectra") -> np.ndarray:
    """Eq. 6.10 with the RGBXY appearance space, k = 3 and equal primed weights (6.11); with
    ``p_dyn > 0`` the dynamic-range compression of Eq. 10.2, so that shading does not
    separate the appearance neighbours of one material; ``prior`` as in
    :func:`recon.spectralize.solve.build_problem`, ``"chosen"`` for the one
    :func:`recon.spectralize.choose_prior` picks."""
    if prior == "chosen":
        prior = choose_prior(
            data.rgb, data.response, data.pixels, data.spectra, p_dyn=p_dyn, **_SPECTRALIZATION
        ).prior
    return _solve(data, p_dyn, prior)


def _solve(data: SparseInput, p_dyn: float, prior: str) -> np.ndarray:
    return spectralize(
        data.rgb,
        data.response,
        known_pixels=data.pixels,
        known_spectra=data.spectra,
        p_dyn=p_dyn,
        prior=prior,
        **_SPECTRALIZATION,
    )


def _spectralization_kriged(data: SparseInput) -> np.ndarray:
    """The chosen prior's spectralization blended with Murakami's kriged estimate by the weight
    the same folds' held-out spots choose
    (:mod:`recon.image_spectralization.kriging_blend`)."""
    choice = choose_prior(data.rgb, data.response, data.pixels, data.spectra, **_SPECTRALIZATION)
    return _blended(data, choice, _solve(data, 0.0, choice.prior))


def _spectralization_chosen_appearance(data: SparseInput) -> np.ndarray:
    """As :func:`_spectralization_kriged`, the appearance space (RGBXY or the one learned from
    the known spectra) chosen with the prior by the same folds
    (:func:`recon.spectralize.choose_appearance`); as ``spectwin spectralize`` does, RGBXY is
    solved hierarchically (in the folds and finally) on images of
    :data:`recon.spectralize.hierarchy.MIN_PIXELS` or more."""
    settings = {key: value for key, value in _SPECTRALIZATION.items() if key != "appearance"}
    stride = hierarchy.stride_for(data.rgb.shape)
    chosen = choose_appearance(
        data.rgb, data.response, data.pixels, data.spectra, sample_stride=stride, **settings
    )
    solved = hierarchy.reconstruct_image(
        data.rgb,
        data.response,
        point_spectra=PointSpectra(data.pixels, data.spectra),
        stride=stride,
        graph=chosen.graph,
        prior=chosen.prior_choice.prior,
        **settings,
        **chosen.energy,
    )
    return _blended(data, chosen.prior_choice, solved)


def _blended(data: SparseInput, choice: PriorChoice, solved: np.ndarray) -> np.ndarray:
    """``solved`` blended with Murakami's kriged estimate by the weight ``choice``'s folds'
    held-out spots choose."""
    weight = choose_kriging_weight(data.rgb, data.response, data.pixels, data.spectra, choice)
    return blend_with_kriging(
        solved, data.rgb, data.response, data.pixels, data.spectra, weight.kriging_weight
    )


def _a_plus(data: SparseInput, ridge_lambda: float) -> np.ndarray:
    """A+ estimates the response from the training pairs (response=None) and codes spectra with
    8 atoms (its default); with fewer bands than 8, with all of them."""
    return baselines.recover(
        data.rgb,
        None,
        method="a_plus",
        known_pixels=data.pixels,
        known_spectra=data.spectra,
        sparsity=min(8, data.spectra.shape[1]),
        ridge_lambda=ridge_lambda,
    )


METHODS: dict[str, Callable[[SparseInput], np.ndarray]] = {
    "spectralization": _spectralization,
    "spectralization p_dyn=1": lambda d: _spectralization(d, p_dyn=1.0),
    "spectralization regression prior": lambda d: _spectralization(d, prior="regression"),
    "spectralization chosen prior": lambda d: _spectralization(d, prior="chosen"),
    "spectralization chosen prior and kriging": _spectralization_kriged,
    "spectralization chosen appearance, prior and kriging": _spectralization_chosen_appearance,
    "imai": lambda d: baselines.recover(d.rgb, d.response, method="imai"),
    "hardeberg": lambda d: baselines.recover(
        d.rgb, None, method="hardeberg", known_pixels=d.pixels, known_spectra=d.spectra
    ),
    "murakami": lambda d: baselines.recover(
        d.rgb, d.response, method="murakami", known_pixels=d.pixels, known_spectra=d.spectra
    ),
    "dong": lambda d: baselines.recover(d.rgb, d.response, method="dong", known_spectra=d.spectra),
    "a_plus": lambda d: _a_plus(d, 0.1),
    "a_plus lambda=1e-5": lambda d: _a_plus(d, 1e-5),
}
"""The protocols' contenders by name: spectralization in six settings, and the baselines of
:data:`recon.baselines.RECOVERY_METHODS` under their names there, called through
:func:`recon.baselines.recover` with what each uses (``"a_plus lambda=1e-5"`` is ``"a_plus"``
with ``ridge_lambda=1e-5``, thesis Sec. 10.4.4). Imai cannot use the known spectra (section 7),
Hardeberg uses no response and Dong no pixel positions. Smits 1999 and Jakob 2019 expect sRGB
reflectance input, not camera values, and are left out of these camera-based protocols."""


@dataclass(frozen=True)
class ProtocolResult:
    """Per-method relative error maps (Eq. 6.8, %, ``(H, W)``) and estimates."""

    error_maps: dict[str, np.ndarray]
    estimates: dict[str, np.ndarray]
    known_pixels: int

    @property
    def mean_errors(self) -> dict[str, float]:
        """Mean relative error per method, %."""
        return {name: float(np.mean(m)) for name, m in self.error_maps.items()}


def _check_case(truth: np.ndarray, response: np.ndarray, methods: Sequence[str]) -> None:
    if truth.ndim != 3 or not np.all(np.isfinite(truth)):
        raise InputError(
            f"truth: expected a finite (H, W, K) spectral image, got shape {truth.shape}"
        )
    if response.ndim != 2 or response.shape[0] != truth.shape[-1]:
        raise InputError(
            f"response: expected ({truth.shape[-1]}, channels) to match the truth's bands, got "
            f"{response.shape}"
        )
    unknown = sorted(set(methods) - set(METHODS))
    if unknown:
        raise InputError(f"methods: unknown {unknown}; expected some of {sorted(METHODS)}")


def run_protocol(
    truth: np.ndarray,
    response: np.ndarray,
    mask: np.ndarray,
    *,
    noise_fraction: float = 0.01,
    methods: Sequence[str] = tuple(METHODS),
    seed: int = 0,
) -> ProtocolResult:
    """Reconstruct ``truth`` from noisy RGB plus its spectra where ``mask`` is set.

    Parameters
    ----------
    truth
        ``(H, W, K)`` reference spectral image.
    response
        ``(K, C)`` camera-times-light matrix of Eq. 7.1.
    mask
        ``(H, W)`` booleans: pixels whose true spectrum is handed to the methods.
    noise_fraction
        Gaussian RGB noise :math:`\\sigma` as a fraction of the mean (chapter 7: 1 %).
    methods
        Names from :data:`METHODS`.
    seed
        Seed of the RGB noise.

    Returns
    -------
    ProtocolResult
    """
    truth, response = np.asarray(truth, np.float64), np.asarray(response, np.float64)
    _check_case(truth, response, methods)
    pixels, spectra = known_spectra_from_mask(truth, mask)
    rgb = add_rgb_noise(truth @ response, noise_fraction, np.random.default_rng(seed))
    data = SparseInput(rgb, response, pixels, spectra)
    estimates = {name: METHODS[name](data).reshape(truth.shape) for name in methods}
    maps = {name: relative_error(est, truth) for name, est in estimates.items()}
    return ProtocolResult(maps, estimates, int(pixels.size))


def _curves(results: list[ProtocolResult], methods: Sequence[str]) -> dict[str, list[float]]:
    """Mean relative error per method along a sweep of protocol runs."""
    return {name: [result.mean_errors[name] for result in results] for name in methods}


def spot_count_sweep(
    truth: np.ndarray,
    response: np.ndarray,
    *,
    counts: Sequence[int] = (25, 50, 100, 250, 500, 1000),
    methods: Sequence[str] = ("spectralization", "hardeberg", "dong", "murakami"),
    noise_fraction: float = 0.01,
    seed: int = 0,
) -> dict[str, list[float]]:
    """Mean relative error per method against the number of whisk-broom spots (Fig. 7.9)."""
    results = [
        run_protocol(
            truth,
            response,
            whisk_broom_mask(truth.shape[:2], n_spots=int(count)),
            noise_fraction=noise_fraction,
            methods=methods,
            seed=seed,
        )
        for count in counts
    ]
    return _curves(results, methods)


def noise_sweep(
    truth: np.ndarray,
    response: np.ndarray,
    *,
    noise_fractions: Sequence[float] = (0.005, 0.01, 0.02, 0.03, 0.05),
    methods: Sequence[str] = ("spectralization", "hardeberg", "dong", "murakami"),
    seed: int = 0,
) -> dict[str, list[float]]:
    """Mean relative error per method against RGB noise, 250 whisk-broom spots (Fig. 7.10)."""
    mask = whisk_broom_mask(truth.shape[:2])
    results = [
        run_protocol(
            truth, response, mask, noise_fraction=float(fraction), methods=methods, seed=seed
        )
        for fraction in noise_fractions
    ]
    return _curves(results, methods)
