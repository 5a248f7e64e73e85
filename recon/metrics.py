"""Error measures between estimated and true spectra.

References
----------
- The thesis, Eq. 6.8: the mean relative error in percent,
  :math:`\\Upsilon_{rel}(x, y) = \\frac{100}{k} \\sum_i \\frac{|x_i - y_i|}{|x_i| + \\epsilon}`,
  with :math:`\\epsilon = 10^{-3}`.
"""

from __future__ import annotations

import numpy as np

from recon.errors import SpectwinInputError

__all__ = ["peak_relative_rmse", "relative_error"]


def relative_error(estimate: np.ndarray, truth: np.ndarray, eps: float = 1e-3) -> np.ndarray:
    """Per-spectrum mean relative error in percent (Eq. 6.8), band axis last.

    ``truth`` is the reference :math:`x` of Eq. 6.8; ``eps`` down-weights dark, noisy values.
    """
    estimate, truth = np.asarray(estimate, np.float64), np.asarray(truth, np.float64)
    if estimate.shape != truth.shape:
        raise SpectwinInputError(
            f"relative_error: estimate {estimate.shape} and truth {truth.shape} differ in shape"
        )
    if not eps > 0:
        raise SpectwinInputError(f"eps: expected a positive constant, got {eps}")
    return 100.0 * np.mean(np.abs(estimate - truth) / (np.abs(truth) + eps), axis=-1)


def peak_relative_rmse(
    estimate: np.ndarray, truth: np.ndarray, *, fit_scale: bool = True
) -> np.ndarray:
    """Per-column RMSE of ``(K, n)`` curves as a fraction of the true peak.

    With ``fit_scale`` the estimate is first multiplied by the least-squares global factor
    (one for all columns): for camera responses, whose overall scale a photograph cannot fix.
    """
    estimate, truth = np.asarray(estimate, np.float64), np.asarray(truth, np.float64)
    if estimate.shape != truth.shape:
        raise SpectwinInputError(
            f"peak_relative_rmse: estimate {estimate.shape} and truth {truth.shape} differ in shape"
        )
    scale = np.sum(estimate * truth) / np.sum(estimate * estimate) if fit_scale else 1.0
    return np.sqrt(np.mean((scale * estimate - truth) ** 2, axis=0)) / np.abs(truth).max()
