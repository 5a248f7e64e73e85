"""Spectral A+ (Aeschbacher, Wu & Timofte 2017): anchored neighbourhood regression on a sparse
spectral dictionary (thesis Sec. 5, 7.1, 10.4.4).

:func:`spectral_a_plus` takes the paper's arguments, :func:`aplus` the same in the project's
``(rgb, response, ...)`` order.

References
----------
- Aeschbacher, J., Wu, J., & Timofte, R. (2017). In defense of shallow learned spectral
  reconstruction from RGB images. Proc. IEEE ICCV Workshops, 471-479.
- Timofte, R., De Smet, V., & Van Gool, L. (2014). A+: Adjusted anchored neighborhood regression
  for fast super-resolution. Asian Conference on Computer Vision, 111-126.
- Aharon, M., Elad, M., & Bruckstein, A. (2006). K-SVD: An algorithm for designing
  overcomplete dictionaries for sparse representation. IEEE Transactions on Signal Processing,
  54(11), 4311-4322.
- Pati, Y. C., Rezaiifar, R., & Krishnaprasad, P. S. (1993). Orthogonal matching pursuit:
  recursive function approximation with applications to wavelet decomposition. Asilomar
  Conference on Signals, Systems and Computers.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from sklearn.decomposition import sparse_encode

from recon.baselines.common import (
    CHUNK_ELEMENTS,
    check_count,
    check_image,
    check_known_rgb,
    check_positive,
    check_response,
    check_spectra,
)
from recon.errors import SpectwinInputError

__all__ = ["aplus", "spectral_a_plus"]


def _ksvd(
    data: np.ndarray, n_atoms: int, sparsity: int, n_iter: int, rng: np.random.Generator
) -> np.ndarray:
    """K-SVD dictionary ``(n_atoms, K)`` of the rows of ``data`` (Aharon et al. 2006).

    Sparse coding by OMP with exactly ``sparsity`` non-zeros (scikit-learn's
    ``sparse_encode``), then each atom and its coefficients are updated by the best rank-one
    approximation of the residual of the samples that use it. Unused atoms are replaced by the
    worst-represented sample.
    """
    dictionary = data[rng.choice(len(data), n_atoms, replace=False)].copy()
    for _ in range(n_iter):
        with warnings.catch_warnings():
            # Degenerate training sets (few distinct spectra) make OMP stop early; harmless.
            warnings.filterwarnings("ignore", message="Orthogonal matching pursuit ended")
            codes = sparse_encode(
                data, dictionary, algorithm="omp", n_nonzero_coefs=sparsity, check_input=False
            )
        for atom in range(n_atoms):
            users = np.flatnonzero(codes[:, atom])
            if users.size == 0:
                residual = np.einsum("ij,ij->i", *(2 * [data - codes @ dictionary]))
                worst = int(np.argmax(residual))
                dictionary[atom] = data[worst]
                continue
            codes[users, atom] = 0.0
            error = data[users] - codes[users] @ dictionary
            left, singular, right = np.linalg.svd(error, full_matrices=False)
            dictionary[atom] = right[0]
            codes[users, atom] = singular[0] * left[:, 0]
    return dictionary


def spectral_a_plus(
    rgb: np.ndarray,
    training_spectra: np.ndarray,
    training_rgb: np.ndarray | None = None,
    *,
    known_pixels: np.ndarray | None = None,
    response: np.ndarray | None = None,
    n_atoms: int = 64,
    sparsity: int = 8,
    ridge_lambda: float = 0.1,
    neighbourhood_size: int = 64,
    n_iter: int = 10,
    random_state: int | None = 0,
) -> np.ndarray:
    """Spectral A+: anchored neighbourhood regression (Aeschbacher, Wu & Timofte 2017).

    Training, following the paper (which builds on A+ by Timofte et al. 2014):

    1. A spectral dictionary of ``n_atoms`` atoms is learned from the (l2-normalized) training
       spectra by K-SVD with OMP sparse coding of ``sparsity`` non-zeros (:func:`_ksvd`).
    2. The anchors are the atoms projected to RGB through ``response`` and normalized.
    3. For every anchor the ``neighbourhood_size`` training samples whose normalized RGB is most
       correlated with it (largest :math:`|\\langle \\hat v, a\\rangle|`) form its neighbourhood,
       and a ridge regression from their RGB to their spectra is precomputed:
       :math:`P_a = (\\hat V_N^T \\hat V_N + \\lambda I)^{-1} \\hat V_N^T \\hat S_N`, where each
       sample is divided by its RGB norm (:math:`\\hat v = v/\\|v\\|`, :math:`\\hat s = s/\\|v\\|`).

    Reconstruction: each pixel's normalized RGB picks the anchor of highest absolute
    correlation; its spectrum is :math:`\\|v\\| \\, \\hat v P_a = v P_a` (the norm re-applied).
    Black pixels map to zero spectra.

    The defaults sparsity 8 and :math:`\\lambda = 0.1` are the parameters of Aeschbacher et al.
    quoted in thesis Sec. 7.1 (Sec. 10.4.4 found :math:`\\lambda = 10^{-5}` better on BTF data).
    ``n_atoms``, ``neighbourhood_size`` and ``n_iter`` are sized for a few hundred training
    spectra (the thesis passes 250); the paper used far larger training sets.

    Parameters
    ----------
    rgb
        ``(..., C)`` image to reconstruct.
    training_spectra
        ``(m, K)`` training spectra (e.g. the known spectra of the image), m >= ``n_atoms``.
    training_rgb
        ``(m, C)`` RGB of the training spectra. Alternatively give ``known_pixels`` (the RGB is
        read from ``rgb``) or only ``response`` (the RGB is ``training_spectra @ response``).
    known_pixels
        Flat row-major indices into ``rgb.shape[:-1]`` of the training spectra.
    response
        ``(K, C)`` projection used for the anchors. If omitted it is estimated from the training
        pairs by least squares (``training_rgb ~ training_spectra @ response``).
    n_atoms
        Dictionary size (anchors).
    sparsity
        Non-zero coefficients per sample in the K-SVD's OMP, <= min(K, ``n_atoms``).
    ridge_lambda
        Ridge regularization :math:`\\lambda` > 0 of the per-anchor regressions.
    neighbourhood_size
        Training samples per anchor (at most m are used).
    n_iter
        K-SVD iterations.
    random_state
        Seed of the dictionary initialisation.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra.
    """
    pixels = check_image("rgb", rgb)
    channels = pixels.shape[-1]
    spectra = check_spectra("training_spectra", training_spectra)
    samples, bands = spectra.shape
    matrix = None if response is None else check_response(response, bands, channels)
    flat = pixels.reshape(-1, channels)
    if known_pixels is None and training_rgb is None:
        if matrix is None:
            raise SpectwinInputError(
                "training_rgb: expected training_rgb, known_pixels or response to know the RGB "
                "of the training spectra, got none of them"
            )
        train_rgb = spectra @ matrix
    else:
        train_rgb = check_known_rgb(
            flat,
            spectra,
            known_pixels,
            training_rgb,
            pixels.shape[:-1],
            ("known_pixels", "training_rgb"),
        )
    n_atoms = check_count("n_atoms", n_atoms, 1, samples)
    sparsity = check_count("sparsity", sparsity, 1, min(bands, n_atoms))
    ridge = check_positive("ridge_lambda", ridge_lambda)
    neighbours = min(check_count("neighbourhood_size", neighbourhood_size, 1), samples)
    n_iter = check_count("n_iter", n_iter, 0)

    rgb_norm = np.linalg.norm(train_rgb, axis=1)
    usable = rgb_norm > 0
    if not np.any(usable) or not np.any(spectra):
        raise SpectwinInputError(
            "training_spectra / training_rgb: all training samples are black (zero RGB or zero "
            "spectrum); nothing to learn from"
        )
    if matrix is None:
        matrix = np.linalg.lstsq(spectra, train_rgb, rcond=None)[0]

    spectra_norm = np.linalg.norm(spectra, axis=1, keepdims=True)
    shapes = spectra[spectra_norm[:, 0] > 0] / spectra_norm[spectra_norm[:, 0] > 0]
    if len(shapes) < n_atoms:
        raise SpectwinInputError(
            f"n_atoms: expected at most the number of non-zero training spectra "
            f"({len(shapes)}), got {n_atoms}"
        )
    rng = np.random.default_rng(random_state)
    atoms = _ksvd(shapes, n_atoms, sparsity, n_iter, rng)

    anchors = atoms @ matrix  # (n_atoms, C)
    anchor_norm = np.linalg.norm(anchors, axis=1)
    anchors = anchors[anchor_norm > 1e-12 * anchor_norm.max()]
    anchors /= np.linalg.norm(anchors, axis=1, keepdims=True)

    unit_rgb = train_rgb[usable] / rgb_norm[usable, None]
    unit_spectra = spectra[usable] / rgb_norm[usable, None]
    neighbours = min(neighbours, len(unit_rgb))
    correlation = np.abs(unit_rgb @ anchors.T)  # (samples, anchors)
    nearest = np.argpartition(-correlation, neighbours - 1, axis=0)[:neighbours].T
    near_rgb = unit_rgb[nearest]  # (anchors, n, C)
    near_spectra = unit_spectra[nearest]  # (anchors, n, K)
    gram = np.einsum("anc,and->acd", near_rgb, near_rgb) + ridge * np.eye(channels)
    projections = np.linalg.solve(gram, np.einsum("anc,ank->ack", near_rgb, near_spectra))

    result = np.empty((len(flat), bands))
    rows_per_chunk = max(1, CHUNK_ELEMENTS // len(anchors))
    for start in range(0, len(flat), rows_per_chunk):
        chunk = flat[start : start + rows_per_chunk]
        norm = np.linalg.norm(chunk, axis=1, keepdims=True)
        unit = np.divide(chunk, norm, out=np.zeros_like(chunk), where=norm > 0)
        best = np.argmax(np.abs(unit @ anchors.T), axis=1)
        result[start : start + len(chunk)] = np.einsum("pc,pck->pk", chunk, projections[best])
    return result.reshape(*pixels.shape[:-1], bands)


def aplus(
    rgb: np.ndarray,
    response: np.ndarray | None,
    training_spectra: np.ndarray,
    training_rgb: np.ndarray | None = None,
    **options: Any,
) -> np.ndarray:
    """:func:`spectral_a_plus` in the project's ``(rgb, response, ...)`` calling order.

    Parameters
    ----------
    rgb
        ``(..., C)`` image to reconstruct.
    response
        ``(K, C)`` projection used for the anchors, or ``None`` to estimate it from the
        training pairs (see :func:`spectral_a_plus`).
    training_spectra, training_rgb
        As in :func:`spectral_a_plus`.
    **options
        The keyword arguments of :func:`spectral_a_plus` (``known_pixels``, ``n_atoms``,
        ``sparsity``, ``ridge_lambda``, ...).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra, those of :func:`spectral_a_plus`.
    """
    return spectral_a_plus(rgb, training_spectra, training_rgb, response=response, **options)
