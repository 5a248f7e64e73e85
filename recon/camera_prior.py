"""A prior over RGB camera spectral responses, learned from measured cameras.

The responses of real cameras are alike: scaled to a peak of one per channel, two or three
principal components explain most of their variation (Jiang et al. 2013, 28 cameras).
``learn_response_prior`` fits, per channel :math:`c`, a probabilistic principal component model
(Tipping & Bishop 1999) to the peak-normalized responses :math:`r_c = R_c / \\max R_c` of a set
of measured cameras: a Gaussian with mean :math:`\\mu_c`, ``components`` principal directions
with their variances, and an isotropic residual variance (the mean of the discarded
eigenvalues, its maximum-likelihood value), whose precision is :math:`\\Sigma_c^{-1}`.

A photograph fixes a response only up to a scale, so the prior scores a response's shape and
leaves its scale free: the energy is the Mahalanobis distance to the nearest multiple of the mean,

.. math::

    E_{prior}(R_c) = \\min_s (R_c - s\\mu_c)^T \\Sigma_c^{-1} (R_c - s\\mu_c) = R_c^T M_c R_c,
    \\qquad M_c = \\Sigma_c^{-1} - \\frac{\\Sigma_c^{-1}\\mu_c \\mu_c^T \\Sigma_c^{-1}}
    {\\mu_c^T \\Sigma_c^{-1} \\mu_c},

a quadratic form, so it enters the linear least-squares steps of the extended estimator
(thesis Eq. 9.6) as rows :math:`L_c R_c` with :math:`L_c^T L_c = M_c`
(``recon.camera_char.estimate_response(..., prior=...)``).

References
----------
- Jiang, J., Liu, D., Gu, J., & Süsstrunk, S. (2013). What is the space of spectral sensitivity
  functions for digital color cameras? IEEE Workshop on Applications of Computer Vision (WACV),
  168-179. doi:10.1109/WACV.2013.6475015
- Tipping, M. E., & Bishop, C. M. (1999). Probabilistic principal component analysis. Journal
  of the Royal Statistical Society B, 61(3), 611-622. doi:10.1111/1467-9868.00196
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.decomposition import PCA

from recon.errors import InputError

__all__ = ["PRIOR_COMPONENTS", "PRIOR_WEIGHT", "ResponsePrior", "learn_response_prior"]

# Chosen by benchmarks/camchar_prior_tuning.py on scenarios the study and the tests do not use.
PRIOR_COMPONENTS = 3
"""Principal directions per channel of the prior learned by :func:`learn_response_prior`."""
PRIOR_WEIGHT = 0.01
"""The prior's weight :math:`\\lambda` in ``recon.camera_char.estimate_response``."""


@dataclass(frozen=True, eq=False)
class ResponsePrior:
    """Per-channel Gaussian over peak-normalized camera responses (module description).

    Attributes
    ----------
    wavelengths_nm
        ``(K,)`` the grid the prior lives on; responses it scores must be on it.
    mean
        ``(K, 3)`` :math:`\\mu_c`, the mean of the peak-normalized training responses.
    precision
        ``(3, K, K)`` :math:`\\Sigma_c^{-1}` of the probabilistic principal component model.
    cameras
        How many measured cameras the prior was learned from.
    """

    wavelengths_nm: np.ndarray
    mean: np.ndarray
    precision: np.ndarray
    cameras: int

    def energy_roots(self) -> np.ndarray:
        """``(3, K, K)`` matrices :math:`L_c` with :math:`L_c^T L_c = M_c` (module description),
        so that :math:`E_{prior}(R_c) = \\|L_c R_c\\|^2`."""
        roots = []
        for channel in range(3):
            precision, mean = self.precision[channel], self.mean[:, channel]
            pulled = precision @ mean
            scale_free = precision - np.outer(pulled, pulled) / (mean @ pulled)
            values, vectors = np.linalg.eigh((scale_free + scale_free.T) / 2)
            roots.append(np.sqrt(np.clip(values, 0.0, None))[:, None] * vectors.T)
        return np.array(roots)

    def energy(self, response: np.ndarray) -> np.ndarray:
        """:math:`E_{prior}(R_c / \\max R_c)` per channel, ``(3,)``, for a ``(K, 3)`` response:
        the squared Mahalanobis distance of its shape to the training cameras' (0 for any
        multiple of the mean, about ``K`` for a typical camera)."""
        response = np.asarray(response, np.float64)
        if response.shape != self.mean.shape:
            raise InputError(
                f"response: expected {self.mean.shape} on the prior's grid, got {response.shape}"
            )
        shape = response / np.abs(response).max(axis=0)
        roots = self.energy_roots()
        return np.array([np.sum((roots[c] @ shape[:, c]) ** 2) for c in range(3)])


def learn_response_prior(
    responses: np.ndarray, wavelengths: np.ndarray, *, components: int = PRIOR_COMPONENTS
) -> ResponsePrior:
    """Learn the prior of the module description from measured camera responses.

    Parameters
    ----------
    responses
        ``(N, K, 3)`` spectral responses of ``N`` cameras on ``wavelengths``, channels R, G, B,
        in any units (each channel is scaled to a peak of one).
    wavelengths
        The ``K`` sample wavelengths in nm, the grid of the estimates the prior will guide.
    components
        Principal directions per channel; the rest of the variation is isotropic.

    Returns
    -------
    ResponsePrior
        Mean and precision per channel.

    References
    ----------
    Tipping & Bishop (1999); ``sklearn.decomposition.PCA`` fits the model (its
    ``noise_variance_`` and ``get_precision``).

    Examples
    --------
    >>> from recon.measured_data import camera_names, read_camera_sensitivities
    >>> from recon.spectra import WavelengthGrid, resample
    >>> grid = WavelengthGrid.regular(380, 780, 10)
    >>> cameras = np.array([
    ...     resample(read_camera_sensitivities(name), grid, method="box").values.T
    ...     for name in camera_names()[1:]
    ... ])
    >>> prior = learn_response_prior(cameras, grid.wavelengths_nm)
    >>> prior.mean.shape, prior.cameras
    ((41, 3), 50)
    """
    responses = np.asarray(responses, np.float64)
    wavelengths = np.asarray(wavelengths, np.float64)
    if responses.ndim != 3 or responses.shape[1:] != (wavelengths.size, 3):
        raise InputError(
            f"responses: expected (cameras, {wavelengths.size}, 3) on the wavelengths, "
            f"got {responses.shape}"
        )
    if not 1 <= components < wavelengths.size:
        raise InputError(f"components: expected 1 to {wavelengths.size - 1}, got {components}")
    if responses.shape[0] < components + 2:
        raise InputError(
            f"responses: expected at least components + 2 = {components + 2} cameras, "
            f"got {responses.shape[0]}"
        )
    peaks = responses.max(axis=1, keepdims=True)
    if not np.all(np.isfinite(responses)) or np.any(peaks <= 0):
        raise InputError("responses: expected finite values with a positive peak in every channel")
    shapes = responses / peaks
    means, precisions = [], []
    for channel in range(3):
        model = PCA(n_components=components, svd_solver="full").fit(shapes[:, :, channel])
        if not model.noise_variance_ > 0:
            raise InputError(
                f"responses: {components} components leave no residual variation: use fewer"
            )
        means.append(model.mean_)
        precisions.append(model.get_precision())
    return ResponsePrior(
        wavelengths_nm=wavelengths.copy(),
        mean=np.array(means).T,
        precision=np.array(precisions),
        cameras=responses.shape[0],
    )
