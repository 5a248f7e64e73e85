"""Dong et al. (2016): a non-negative basis of the known spectra by NMF, coefficients per pixel
from the RGB (thesis Sec. 5, 10.4.3).

References
----------
- Dong, W., Shen, H.-L., Du, X., Shao, S.-J., & Xin, J. H. (2016). Spectral bidirectional
  texture function reconstruction by fusing multiple-color and spectral images. Applied Optics,
  55(36), 10400-10408.
"""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.decomposition import NMF
from sklearn.exceptions import ConvergenceWarning

from recon.baselines.common import (
    check_count,
    check_image,
    check_positive,
    check_response,
    check_spectra,
)
from recon.errors import InputError

__all__ = ["dong"]


def dong(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    known_spectra: np.ndarray,
    n_components: int = 3,
    random_state: int | None = 0,
    max_iter: int = 10000,
    tol: float = 1e-6,
) -> np.ndarray:
    """Non-negative spectral basis from known spectra, coefficients from RGB (Dong et al. 2016).

    The known spectra (in the paper: one spectral image of the material under spherical
    illumination) are factorized by non-negative matrix factorization,
    :math:`S_{known} \\approx H B` with :math:`B \\ge 0` of shape ``(n_components, K)``
    (scikit-learn's coordinate-descent NMF; Dong et al. cite Kim & Park's active-set NMF). Each
    pixel's coefficients :math:`c` solve :math:`v = c\\,(B R)` in the least-squares sense (a
    square ``3 x 3`` system for three components and RGB; minimal norm when
    ``n_components > C``) and the spectrum is :math:`s = c B`. The coefficients are not
    constrained to be non-negative. As with :func:`~recon.baselines.hardeberg`, the results
    lie in an ``n_components``-dimensional subspace (thesis Sec. 5, 10.4.3).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values.
    response
        ``(K, C)`` projection with ``rgb = spectra @ response``.
    known_spectra
        ``(m, K)`` non-negative spectra to build the basis from.
    n_components
        Size of the basis, 1 <= ``n_components`` <= K; 3 in the paper.
    random_state
        Seed of the NMF initialisation (``nndsvda`` is deterministic; kept for solvers that
        randomise).
    max_iter, tol
        Iteration limit and stopping tolerance of the NMF solver (``tol=1e-6`` fits 250
        spectra of an exact 3-component model to ~1e-4 relative error in ~0.1 s).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra.
    """
    pixels = check_image("rgb", rgb)
    spectra = check_spectra("known_spectra", known_spectra)
    matrix = check_response(response, spectra.shape[1], pixels.shape[-1])
    components = check_count("n_components", n_components, 1, spectra.shape[1])
    check_count("max_iter", max_iter, 1)
    tol = check_positive("tol", tol)
    if spectra.min() < 0:
        raise InputError(
            f"known_spectra: NMF needs non-negative spectra, found a minimum of "
            f"{spectra.min():g}; clip noise below zero first"
        )
    if not np.any(spectra):
        raise InputError("known_spectra: all zero, no basis can be learned")
    factorization = NMF(
        n_components=components,
        init="nndsvda",
        solver="cd",
        tol=tol,
        max_iter=max_iter,
        random_state=random_state,
    )
    with warnings.catch_warnings():
        # The basis is used as it stands after max_iter iterations (the paper's fixed budget);
        # a fit that stops short of tol is not an error the caller could act on.
        warnings.simplefilter("ignore", ConvergenceWarning)
        factorization.fit(spectra)
    basis = factorization.components_  # (n_components, K)
    coefficients = pixels @ np.linalg.pinv(basis @ matrix)  # (..., n_components)
    return coefficients @ basis
