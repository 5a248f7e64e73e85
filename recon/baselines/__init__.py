"""Spectral recovery methods that compete with spectralization: array in, array out.

Every function recovers spectra from RGB (or any ``C``-channel broadband) data. Conventions:

- Spectral images are float arrays of shape ``(..., K)``, band axis last; RGB images are
  ``(..., C)`` with ``C = 3`` for an RGB camera.
- ``response`` is the ``(K, C)`` projection of the camera (and light) so that
  ``rgb = spectra @ response``: thesis Eq. 6.2 (:math:`v = s R_{cam}`) and Eq. 7.1
  (:math:`V = S R_{cam}`).
- Known spectra are the rows of ``known_spectra`` ``(m, K)``. Where a method needs their RGB it
  takes it from the RGB image at ``known_pixels``: **flat, row-major (C-order) indices into the
  image's leading dimensions** (``rgb.shape[:-1]``), one per row of ``known_spectra``, all
  distinct. For a 2-D image use ``np.ravel_multi_index((rows, cols), rgb.shape[:2])``; for a
  boolean mask ``np.flatnonzero(mask)`` (then the spectra must be in the mask's row-major order).
- Bad input raises :class:`recon.errors.SpectwinInputError` naming the argument.

Methods (the thesis compares them with spectralization in chapter 7, Sec. 7.1-7.6, and in
Sec. 10.4.3-10.4.4):

- :func:`imai`: pseudo-inverse :math:`S = V R^+`, the minimal-norm inverse matrix (Sec. 6.1).
- :func:`hardeberg`: the inverse matrix trained on known spectra,
  :math:`W = \\arg\\min \\|V_{known} W - S_{known}\\|^2` (Sec. 6.1).
- :func:`murakami_2007`: Gaussian-prior (Wiener) estimate from the known spectra's statistics
  plus a spatially interpolated correction at the known points (Sec. 5, 7.1).
- :func:`dong_2016`: a non-negative basis of the known spectra by NMF, coefficients per pixel
  from the RGB (Sec. 5, 10.4.3).
- :func:`spectral_a_plus`: anchored neighbourhood regression on a sparse spectral dictionary
  (Sec. 5, 7.1, 10.4.4; defaults sparsity 8 and :math:`\\lambda = 0.1` as quoted in Sec. 7.1).
- :func:`smits_1999`, :func:`jakob_2019`: heuristic RGB-to-reflectance upsampling that uses no
  known spectra (Sec. 7.1); input is linear RGB with sRGB primaries, see each function.

References
----------
- The thesis, Sec. 6.1 (inverse-matrix methods, Eq. 6.1-6.2), chapter 7 (comparisons).
- Imai, F. H., & Berns, R. S. (1999). Spectral estimation using trichromatic digital cameras.
  Proc. International Symposium on Multispectral Imaging and Color Reproduction for Digital
  Archives, 42-49.
- Hardeberg, J. Y., Schmitt, F., Brettel, H., Crettez, J.-P., & Maitre, H. (1999).
  Multispectral image acquisition and simulation of illuminant changes. In Colour Imaging:
  Vision and Technology (pp. 145-164). Wiley.
- Murakami, Y., Ietomi, K., Yamaguchi, M., & Ohyama, N. (2007). Maximum a posteriori
  estimation of spectral reflectance from color image and multipoint spectral measurements.
  Applied Optics, 46(28), 7068-7082.
- Dong, W., Shen, H.-L., Du, X., Shao, S.-J., & Xin, J. H. (2016). Spectral bidirectional
  texture function reconstruction by fusing multiple-color and spectral images. Applied Optics,
  55(36), 10400-10408.
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
- Smits, B. (1999). An RGB-to-spectrum conversion for reflectances. Journal of Graphics Tools,
  4(4), 11-22.
- Jakob, W., & Hanika, J. (2019). A low-dimensional function space for efficient spectral
  upsampling. Computer Graphics Forum, 38(2), 147-155.
"""

from __future__ import annotations

import contextlib
import functools
import io
import warnings

import colour
import numpy as np
from colour.recovery import LUT3D_Jakob2019, RGB_to_sd_Smits1999
from scipy import linalg, spatial
from sklearn.decomposition import NMF, sparse_encode
from sklearn.exceptions import ConvergenceWarning

from recon.errors import SpectwinInputError
from recon.spectra import WavelengthGrid

__all__ = [
    "aplus",
    "dong",
    "dong_2016",
    "hardeberg",
    "imai",
    "jakob2019",
    "jakob_2019",
    "murakami",
    "murakami_2007",
    "smits",
    "smits_1999",
    "spectral_a_plus",
]

_CHUNK_ELEMENTS = 1 << 22  # pixels x (known points or atoms) evaluated at once
_CMFS_NAME = "CIE 1931 2 Degree Standard Observer"


# --------------------------------------------------------------------------------------------
# Validation helpers
# --------------------------------------------------------------------------------------------


def _float_array(name: str, value: object) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise SpectwinInputError(f"{name}: expected a numeric array, got {type(value)}") from error
    bad = int(np.size(array) - np.count_nonzero(np.isfinite(array)))
    if bad:
        raise SpectwinInputError(
            f"{name}: expected finite values, found {bad} NaN or infinite entries"
        )
    return array


def _image(name: str, value: object, channels: int | None = None) -> np.ndarray:
    """A ``(..., C)`` image with at least one pixel."""
    array = _float_array(name, value)
    if array.ndim < 1 or array.shape[-1] < 1 or array.size == 0:
        raise SpectwinInputError(
            f"{name}: expected an array of shape (..., C) with C >= 1 channels and at least one "
            f"pixel, got shape {array.shape}"
        )
    if channels is not None and array.shape[-1] != channels:
        raise SpectwinInputError(
            f"{name}: expected {channels} channels on the last axis, got shape {array.shape}"
        )
    return array


def _response(value: object, bands: int | None, channels: int) -> np.ndarray:
    """A ``(K, C)`` response whose C matches the RGB data and K the spectra (if known)."""
    response = _float_array("response", value)
    if response.ndim != 2 or response.shape[1] != channels:
        raise SpectwinInputError(
            f"response: expected shape (K, {channels}) so that rgb = spectra @ response "
            f"(thesis Eq. 6.2), got shape {response.shape}"
        )
    if bands is not None and response.shape[0] != bands:
        raise SpectwinInputError(
            f"response: has {response.shape[0]} bands but the spectra have K = {bands}; "
            f"expected shape ({bands}, {channels})"
        )
    if response.shape[0] < 1 or not np.any(response):
        raise SpectwinInputError("response: expected a non-zero (K, C) matrix with K >= 1")
    return response


def _spectra(name: str, value: object, bands: int | None = None) -> np.ndarray:
    """``(m, K)`` known or training spectra, at least one."""
    spectra = _float_array(name, value)
    if spectra.ndim != 2:
        raise SpectwinInputError(
            f"{name}: expected a 2-D array of shape (m, K), one spectrum per row, got shape "
            f"{spectra.shape}"
        )
    if spectra.shape[0] < 1:
        raise SpectwinInputError(
            f"{name}: no known spectra; expected shape (m, K) with m >= 1, got {spectra.shape}"
        )
    if spectra.shape[1] < 1:
        raise SpectwinInputError(f"{name}: expected K >= 1 bands, got shape {spectra.shape}")
    if bands is not None and spectra.shape[1] != bands:
        raise SpectwinInputError(
            f"{name}: has K = {spectra.shape[1]} bands, expected {bands} (the response's K)"
        )
    return spectra


def _known_pixels(value: object, n_pixels: int, count: int, image_shape: tuple) -> np.ndarray:
    """Distinct flat row-major indices into the image's leading dimensions."""
    indices = np.asarray(value)
    if indices.dtype == bool:
        raise SpectwinInputError(
            "known_pixels: expected flat integer indices into rgb.shape[:-1], got a boolean "
            "mask; pass np.flatnonzero(mask) (rows of known_spectra in row-major mask order)"
        )
    if indices.ndim != 1 or not (np.issubdtype(indices.dtype, np.integer) or indices.size == 0):
        raise SpectwinInputError(
            f"known_pixels: expected a 1-D array of integer flat indices into rgb.shape[:-1] "
            f"= {image_shape}, got dtype {indices.dtype} and shape {indices.shape}"
        )
    indices = indices.astype(np.int64)
    if indices.size != count:
        raise SpectwinInputError(
            f"known_pixels: expected one index per known spectrum ({count}), got {indices.size}"
        )
    if indices.size and (indices.min() < 0 or indices.max() >= n_pixels):
        raise SpectwinInputError(
            f"known_pixels: expected flat indices in [0, {n_pixels}) for an image of shape "
            f"{image_shape}, got range [{indices.min()}, {indices.max()}]"
        )
    if np.unique(indices).size != indices.size:
        raise SpectwinInputError("known_pixels: expected distinct pixel indices, found repeats")
    return indices


def _known_rgb(
    pixels: np.ndarray,
    known_spectra: np.ndarray,
    known_pixels: object,
    known_rgb: object,
    image_shape: tuple,
    names: tuple[str, str] = ("known_pixels", "known_rgb"),
) -> np.ndarray:
    """RGB of the known spectra: from the image at ``known_pixels`` or given as ``known_rgb``."""
    if (known_pixels is None) == (known_rgb is None):
        raise SpectwinInputError(
            f"{names[0]} / {names[1]}: expected exactly one of them (the pixels of the known "
            f"spectra in rgb, or their RGB values), got "
            f"{'both' if known_pixels is not None else 'neither'}"
        )
    if known_pixels is not None:
        index = _known_pixels(known_pixels, len(pixels), len(known_spectra), image_shape)
        return pixels[index]
    values = _image(names[1], known_rgb, pixels.shape[-1])
    if values.shape != (len(known_spectra), pixels.shape[-1]):
        raise SpectwinInputError(
            f"{names[1]}: expected shape ({len(known_spectra)}, {pixels.shape[-1]}), one RGB "
            f"per known spectrum, got {values.shape}"
        )
    return values


def _positive(name: str, value: float, allow_zero: bool = False) -> float:
    value = float(value)
    if not np.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise SpectwinInputError(f"{name}: expected a finite number {bound}, got {value}")
    return value


def _count(name: str, value: object, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SpectwinInputError(f"{name}: expected an integer, got {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        upper = f" and <= {high}" if high is not None else ""
        raise SpectwinInputError(f"{name}: expected an integer >= {low}{upper}, got {value}")
    return value


def _reflectance_rgb(rgb: object) -> np.ndarray:
    array = _image("rgb", rgb, 3)
    if array.min() < 0 or array.max() > 1:
        raise SpectwinInputError(
            f"rgb: expected linear sRGB reflectance values in [0, 1], got range "
            f"[{array.min():g}, {array.max():g}]; map camera RGB to linear sRGB and clip first"
        )
    return array


# --------------------------------------------------------------------------------------------
# Inverse-matrix methods (thesis Sec. 6.1)
# --------------------------------------------------------------------------------------------


def imai(rgb: np.ndarray, response: np.ndarray) -> np.ndarray:
    """Minimal-norm spectra :math:`S = V R^+` (Imai & Berns 1999; thesis Sec. 6.1).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values :math:`V`.
    response
        ``(K, C)`` projection :math:`R` with ``rgb = spectra @ response`` (Eq. 6.2).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra. For a response of full column rank they reproduce ``rgb`` exactly
        and have no component in the metameric-black space :math:`\\{s : s R = 0\\}`: they are
        the minimal-norm solution, so every reconstructed spectrum lies in the C-dimensional
        span of the response curves.
    """
    pixels = _image("rgb", rgb)
    matrix = _response(response, None, pixels.shape[-1])
    return pixels @ np.linalg.pinv(matrix)


def hardeberg(
    rgb: np.ndarray,
    known_spectra: np.ndarray,
    known_pixels: np.ndarray | None = None,
    *,
    known_rgb: np.ndarray | None = None,
) -> np.ndarray:
    """Trained inverse matrix (Hardeberg et al. 1999; thesis Sec. 6.1).

    :math:`W = \\arg\\min_W \\|V_{known} W - S_{known}\\|_F^2 = V_{known}^+ S_{known}` is learned
    from the known spectra and their RGB and applied to every pixel: :math:`S = V W`. It needs
    no camera response. All results lie in a C-dimensional subspace of spectral space, so it is
    exact when the scene's spectra span at most C dimensions (and the RGB is noise free) and
    biased otherwise (thesis Sec. 6.1, 7.1).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values.
    known_spectra
        ``(m, K)`` known spectra, m >= 1.
    known_pixels
        Flat row-major indices into ``rgb.shape[:-1]`` where ``known_spectra`` were measured
        (their RGB is read from ``rgb``). Give this or ``known_rgb``.
    known_rgb
        ``(m, C)`` RGB of the known spectra, for training data that is not in the image.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra.
    """
    pixels = _image("rgb", rgb)
    spectra = _spectra("known_spectra", known_spectra)
    flat = pixels.reshape(-1, pixels.shape[-1])
    train_rgb = _known_rgb(flat, spectra, known_pixels, known_rgb, pixels.shape[:-1])
    inverse = np.linalg.pinv(train_rgb) @ spectra  # (C, K)
    return pixels @ inverse


# --------------------------------------------------------------------------------------------
# Murakami et al. 2007
# --------------------------------------------------------------------------------------------


def murakami_2007(
    rgb: np.ndarray,
    response: np.ndarray,
    known_spectra: np.ndarray,
    known_pixels: np.ndarray,
    *,
    correlation_length: float | None = None,
    rgb_noise_std: float = 0.0,
    nugget: float = 0.0,
) -> np.ndarray:
    """Gaussian-prior estimate with spatial correction from point spectra (Murakami et al. 2007).

    Our reading of Murakami et al.'s MAP estimate, in two steps:

    1. **Global estimate** (the Gaussian prior): mean :math:`\\mu` and covariance :math:`\\Sigma`
       of the known spectra give the Wiener (linear MMSE) estimate for every pixel,
       :math:`\\hat s = \\mu + (v - \\mu R)(R^T \\Sigma R + \\sigma^2 I)^{-1} R^T \\Sigma`.
       A tiny ridge (:math:`10^{-8}` of the mean variance) keeps :math:`\\Sigma` positive definite
       so the estimate reproduces noise-free RGB exactly.
    2. **Spatial correction**: at the known pixels the residuals
       :math:`e_j = s_j - \\hat s(x_j)` are projected onto the camera's metameric-black space
       :math:`\\{e : e R = 0\\}` (with noise-free RGB they already lie there, and this is then
       the range of the posterior covariance) and interpolated over the image by simple kriging
       with the spatial correlation :math:`\\rho(d) = \\exp(-d / L)` between pixels at distance
       :math:`d`: :math:`\\hat e(x) = k(x)^T (P + \\eta I)^{-1} E` with
       :math:`P_{jl} = \\rho(|x_j - x_l|)`, :math:`k_j(x) = \\rho(|x - x_j|)`. This is the
       conditional mean of the residual field under the separable covariance
       :math:`\\mathrm{Cov}(e(x), e(y)) = \\rho(|x - y|)\\, \\Sigma_e`, in which the spectral factor
       :math:`\\Sigma_e` cancels. Far from every known point the correction fades to zero.

    The result is :math:`\\hat s(x) + \\hat e(x)`. Its RGB equals the input when
    ``rgb_noise_std == 0`` (the correction is metameric black), and with ``nugget == 0`` the
    known spectra are reproduced exactly at their pixels.

    Differences from the paper: the paper derives both steps jointly from one Gaussian model of
    the whole spectral image; here the residual covariance is taken separable (spectral factor
    times spatial factor) so the correction is an interpolation of the residuals, and with RGB
    noise the correction is still restricted to metameric black. The thesis (Sec. 6.2, 7.1)
    notes the method's weakness: the global Gaussian prior fits images with non-normal value
    distributions poorly.

    Parameters
    ----------
    rgb
        ``(H, W, C)`` image (the 2-D layout gives the pixel positions).
    response
        ``(K, C)`` projection with ``rgb = spectra @ response``.
    known_spectra
        ``(m, K)`` spectra measured at ``known_pixels``, m >= 1.
    known_pixels
        Flat row-major indices into ``(H, W)``: pixel ``i`` is at row ``i // W``, column
        ``i % W``.
    correlation_length
        :math:`L` in pixels; default ``0.1 * max(H, W)``.
    rgb_noise_std
        Standard deviation :math:`\\sigma` of the RGB noise in ``rgb`` units (Wiener step).
    nugget
        :math:`\\eta`, noise of the known spectra relative to the residual variance; 0
        interpolates the residuals exactly.

    Returns
    -------
    numpy.ndarray
        ``(H, W, K)`` spectra.

    Notes
    -----
    Cost: one ``m x m`` solve and an ``H W x m`` kernel evaluated in chunks.
    """
    image = _image("rgb", rgb)
    if image.ndim != 3:
        raise SpectwinInputError(
            f"rgb: murakami_2007 needs a 2-D image of shape (H, W, C) for the pixel positions, "
            f"got shape {image.shape}"
        )
    height, width, channels = image.shape
    spectra = _spectra("known_spectra", known_spectra)
    bands = spectra.shape[1]
    matrix = _response(response, bands, channels)
    index = _known_pixels(known_pixels, height * width, len(spectra), (height, width))
    length = (
        0.1 * max(height, width)
        if correlation_length is None
        else _positive("correlation_length", correlation_length)
    )
    noise = _positive("rgb_noise_std", rgb_noise_std, allow_zero=True)
    nugget = _positive("nugget", nugget, allow_zero=True)

    # 1. Wiener estimate under the Gaussian prior of the known spectra.
    mean = spectra.mean(axis=0)
    centred = spectra - mean
    covariance = centred.T @ centred / len(spectra)
    scale = (np.trace(covariance) + mean @ mean) / bands
    covariance += (1e-8 * scale + np.finfo(np.float64).tiny) * np.eye(bands)
    projected = covariance @ matrix  # (K, C)
    system = matrix.T @ projected + noise**2 * np.eye(channels)
    gain = np.linalg.pinv(system, hermitian=True) @ projected.T  # (C, K)
    flat = image.reshape(-1, channels)
    estimate = mean + (flat - mean @ matrix) @ gain

    # 2. Residuals at the known points, metameric black, interpolated by simple kriging.
    black = np.eye(bands) - matrix @ np.linalg.pinv(matrix)
    residuals = (spectra - estimate[index]) @ black
    known_xy = np.column_stack(np.divmod(index, width)).astype(np.float64)
    kernel = np.exp(-spatial.distance.cdist(known_xy, known_xy) / length)
    kernel[np.diag_indices_from(kernel)] += nugget
    try:
        weights = linalg.solve(kernel, residuals, assume_a="pos")
    except (linalg.LinAlgError, ValueError):
        weights = linalg.lstsq(kernel, residuals)[0]
    rows_per_chunk = max(1, _CHUNK_ELEMENTS // len(index))
    all_xy = np.indices((height, width)).reshape(2, -1).T.astype(np.float64)
    for start in range(0, len(flat), rows_per_chunk):
        chunk = slice(start, start + rows_per_chunk)
        near = np.exp(-spatial.distance.cdist(all_xy[chunk], known_xy) / length)
        estimate[chunk] += near @ weights
    return estimate.reshape(height, width, bands)


# --------------------------------------------------------------------------------------------
# Dong et al. 2016
# --------------------------------------------------------------------------------------------


def dong_2016(
    rgb: np.ndarray,
    response: np.ndarray,
    known_spectra: np.ndarray,
    n_components: int = 3,
    *,
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
    constrained to be non-negative. As with :func:`hardeberg`, the results lie in an
    ``n_components``-dimensional subspace (thesis Sec. 5, 10.4.3).

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
    pixels = _image("rgb", rgb)
    spectra = _spectra("known_spectra", known_spectra)
    matrix = _response(response, spectra.shape[1], pixels.shape[-1])
    components = _count("n_components", n_components, 1, spectra.shape[1])
    _count("max_iter", max_iter, 1)
    tol = _positive("tol", tol)
    if spectra.min() < 0:
        raise SpectwinInputError(
            f"known_spectra: NMF needs non-negative spectra, found a minimum of "
            f"{spectra.min():g}; clip noise below zero first"
        )
    if not np.any(spectra):
        raise SpectwinInputError("known_spectra: all zero, no basis can be learned")
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


# --------------------------------------------------------------------------------------------
# Spectral A+ (Aeschbacher, Wu, Timofte 2017)
# --------------------------------------------------------------------------------------------


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
    pixels = _image("rgb", rgb)
    channels = pixels.shape[-1]
    spectra = _spectra("training_spectra", training_spectra)
    samples, bands = spectra.shape
    matrix = None if response is None else _response(response, bands, channels)
    flat = pixels.reshape(-1, channels)
    if known_pixels is None and training_rgb is None:
        if matrix is None:
            raise SpectwinInputError(
                "training_rgb: expected training_rgb, known_pixels or response to know the RGB "
                "of the training spectra, got none of them"
            )
        train_rgb = spectra @ matrix
    else:
        train_rgb = _known_rgb(
            flat,
            spectra,
            known_pixels,
            training_rgb,
            pixels.shape[:-1],
            ("known_pixels", "training_rgb"),
        )
    n_atoms = _count("n_atoms", n_atoms, 1, samples)
    sparsity = _count("sparsity", sparsity, 1, min(bands, n_atoms))
    ridge = _positive("ridge_lambda", ridge_lambda)
    neighbours = min(_count("neighbourhood_size", neighbourhood_size, 1), samples)
    n_iter = _count("n_iter", n_iter, 0)

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
    rows_per_chunk = max(1, _CHUNK_ELEMENTS // len(anchors))
    for start in range(0, len(flat), rows_per_chunk):
        chunk = flat[start : start + rows_per_chunk]
        norm = np.linalg.norm(chunk, axis=1, keepdims=True)
        unit = np.divide(chunk, norm, out=np.zeros_like(chunk), where=norm > 0)
        best = np.argmax(np.abs(unit @ anchors.T), axis=1)
        result[start : start + len(chunk)] = np.einsum("pc,pck->pk", chunk, projections[best])
    return result.reshape(*pixels.shape[:-1], bands)


# --------------------------------------------------------------------------------------------
# Heuristic RGB -> reflectance upsampling (Smits 1999, Jakob & Hanika 2019) via colour
# --------------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=16)
def _smits_matrices(wavelengths: tuple[float, ...]) -> dict[tuple[int, int, int], np.ndarray]:
    """Per channel order ``(lowest, middle, highest)`` the ``(3, K)`` linear map of Smits.

    Within one ordering of R, G, B Smits' spectrum is linear in the RGB (white times the
    smallest value, a secondary times the middle step, a primary times the top step), so three
    evaluations of colour's ``RGB_to_sd_Smits1999`` on the region's edge points fix it.
    """
    wl = np.asarray(wavelengths)
    matrices = {}
    for order in [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]:
        points = np.zeros((3, 3))
        points[0, order[2]] = 1.0
        points[1, [order[1], order[2]]] = 1.0
        points[2, :] = 1.0
        values = np.array([RGB_to_sd_Smits1999(point)[wl] for point in points])
        matrices[order] = np.linalg.solve(points, values)
    return matrices


def smits_1999(rgb: np.ndarray, wavelengths_nm: np.ndarray) -> np.ndarray:
    """Smooth reflectance spectra from RGB by Smits' (1999) method, via colour-science.

    Smits' spectrum is white times the smallest channel plus cyan/magenta/yellow times the
    middle step plus red/green/blue times the top step (colour's
    ``colour.recovery.RGB_to_sd_Smits1999`` and its ``SDS_SMITS1999`` basis spectra). Within one
    ordering of the channels this is linear in RGB, so it is evaluated for all pixels at once.

    Input is **linear RGB with sRGB (ITU-R BT.709) primaries and equal-energy white**: the
    colourspace of colour's Smits implementation, whose illuminant is CIE E (a flat reflectance
    of 1 has RGB (1, 1, 1)). Camera RGB must first be mapped to this space (or from XYZ) by the
    caller. The recovered colour is approximate: Smits' basis spectra are tabulated on ten
    bins between 380 and 720 nm (colour interpolates linearly and extends the end values beyond
    that range).

    Parameters
    ----------
    rgb
        ``(..., 3)`` linear RGB in [0, 1].
    wavelengths_nm
        Strictly increasing output wavelengths in nm (e.g. ``DEFAULT_GRID.wavelengths_nm``).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` reflectances at ``wavelengths_nm``.
    """
    pixels = _reflectance_rgb(rgb)
    grid = WavelengthGrid(wavelengths_nm)
    matrices = _smits_matrices(tuple(float(value) for value in grid.wavelengths_nm))
    flat = pixels.reshape(-1, 3)
    order = np.argsort(flat, axis=1, kind="stable")
    result = np.empty((len(flat), grid.size))
    for key, matrix in matrices.items():
        mask = np.all(order == key, axis=1)
        result[mask] = flat[mask] @ matrix
    return result.reshape(*pixels.shape[:-1], grid.size)


def _jakob_model(coefficients: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Jakob & Hanika's sigmoid-of-quadratic reflectance and its polynomial ``U``."""
    poly = coefficients @ basis
    return 0.5 + poly / (2.0 * np.sqrt(1.0 + poly * poly)), poly


def _jakob_fit(targets: np.ndarray, weights: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Coefficients ``(n, 3)`` whose model spectrum has the target XYZ (``(n, 3)``).

    Levenberg-Marquardt on the XYZ residual, vectorized over colours, with a homotopy from the
    grey of equal luminance (whose flat spectrum is an exact solution) to the target, like the
    lightness walk in colour's LUT generation. ``weights`` ``(K, 3)`` integrate a reflectance to
    XYZ; ``basis`` ``(3, K)`` holds ``x**2, x, 1`` of the normalized wavelength ``x``.
    """
    white = weights.sum(axis=0)
    luminance = np.clip(targets[:, 1] / white[1], 1e-4, 1.0 - 1e-4)
    coefficients = np.zeros_like(targets)
    coefficients[:, 2] = (2 * luminance - 1) / (2 * np.sqrt(luminance * (1 - luminance)))
    grey = luminance[:, None] * white

    def solve(coefficients: np.ndarray, target: np.ndarray, iterations: int) -> np.ndarray:
        damping = np.full(len(target), 1e-2)
        spectra, poly = _jakob_model(coefficients, basis)
        residual = spectra @ weights - target
        error = np.einsum("nc,nc->n", residual, residual)
        for _ in range(iterations):
            slope = 0.5 / (1.0 + poly * poly) ** 1.5  # d reflectance / d poly
            jacobian = np.einsum("nk,kc,jk->ncj", slope, weights, basis)
            normal = np.einsum("nci,ncj->nij", jacobian, jacobian)
            scale = damping * (np.trace(normal, axis1=1, axis2=2) / 3 + 1e-300)
            normal += scale[:, None, None] * np.eye(3)
            gradient = np.einsum("nci,nc->ni", jacobian, residual)
            trial = coefficients - np.linalg.solve(normal, gradient[..., None])[..., 0]
            trial_spectra, trial_poly = _jakob_model(trial, basis)
            trial_residual = trial_spectra @ weights - target
            trial_error = np.einsum("nc,nc->n", trial_residual, trial_residual)
            better = trial_error < error
            coefficients = np.where(better[:, None], trial, coefficients)
            poly = np.where(better[:, None], trial_poly, poly)
            residual = np.where(better[:, None], trial_residual, residual)
            error = np.where(better, trial_error, error)
            damping = np.where(better, damping / 3, damping * 4)
        return coefficients

    steps = 8
    for step in range(1, steps + 1):
        fraction = step / steps
        coefficients = solve(coefficients, grey + fraction * (targets - grey), 10)
    return solve(coefficients, targets, 30)


@functools.lru_cache(maxsize=1)
def _srgb() -> colour.RGB_Colourspace:
    """sRGB with matrices derived from its primaries and white (the published ones are rounded
    to 4 decimals, which would tint greys by ~1e-4)."""
    colourspace = colour.models.RGB_COLOURSPACE_sRGB.copy()
    colourspace.use_derived_transformation_matrices(True)
    return colourspace


@functools.lru_cache(maxsize=4)
def _jakob_lut(size: int, start: float, end: float, interval: float) -> LUT3D_Jakob2019:
    """colour's Jakob & Hanika LUT for sRGB under D65, optimized on the given spectral shape."""
    shape = colour.SpectralShape(start, end, interval)
    cmfs = colour.MSDS_CMFS[_CMFS_NAME].copy().align(shape)
    illuminant = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    lut = LUT3D_Jakob2019()
    with contextlib.redirect_stderr(io.StringIO()):  # colour shows a tqdm progress bar
        lut.generate(_srgb(), cmfs, illuminant, size, lambda *_: None)
    return lut


def jakob_2019(
    rgb: np.ndarray, wavelengths_nm: np.ndarray, *, lut_size: int | None = None
) -> np.ndarray:
    """Smooth reflectance spectra from RGB by Jakob & Hanika's (2019) sigmoid model.

    Each reflectance is :math:`r(\\lambda) = \\frac12 + \\frac{U}{2\\sqrt{1 + U^2}}` with a
    quadratic :math:`U = c_0 \\lambda^2 + c_1 \\lambda + c_2` whose coefficients make the
    spectrum's colour (CIE 1931 2 degree observer, illuminant D65, integrated on
    ``wavelengths_nm``) equal the target. Two ways to get the coefficients:

    - ``lut_size=None`` (default): fit every distinct colour directly, vectorized
      (Levenberg-Marquardt on the XYZ residual starting from the grey of equal luminance). This
      is the optimization colour-science runs per colour in
      ``colour.XYZ_to_sd(..., method="Jakob 2019")``, for all colours at once (~0.2 s per
      colour there, ~0.2 ms here); the target colour is met to about 1e-6 except at the
      unreachable limits 0 and 1 of a channel.
    - ``lut_size=n``: the paper's run-time method, colour's ``LUT3D_Jakob2019`` of size ``n``
      (generated for sRGB and D65 on ``wavelengths_nm``, which must be regular, and cached in
      this process), interpolated. Generation is slow (measured on 2 busy cores: size 4 in
      8-80 s, size 8 in ~3 min) and small tables are coarse (size 4: mean colour error 0.04,
      max 0.3); the published tables have size 64.

    Input is **linear sRGB** (D65 white, :math:`(1, 1, 1)` is a perfect white reflector under
    D65). Camera RGB must first be mapped to linear sRGB (or XYZ) by the caller. As in colour's
    LUT generation, sRGB's white is adapted (CAT02) to the white of a perfect reflector
    integrated on ``wavelengths_nm``, so grey inputs give exactly flat spectra; to check a
    result, integrate it under D65 on the same grid and convert to sRGB with that white. The
    sRGB matrices are derived from the primaries (colour's published ones are rounded).

    Parameters
    ----------
    rgb
        ``(..., 3)`` linear sRGB in [0, 1].
    wavelengths_nm
        Strictly increasing output wavelengths in nm.
    lut_size
        ``None`` to fit each colour, or the size (>= 2) of colour's lookup table to use.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` reflectances in (0, 1) at ``wavelengths_nm``.
    """
    pixels = _reflectance_rgb(rgb)
    grid = WavelengthGrid(wavelengths_nm)
    wl = grid.wavelengths_nm
    flat = pixels.reshape(-1, 3)
    colours, inverse = np.unique(flat, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    if lut_size is not None:
        size = _count("lut_size", lut_size, 2)
        steps = np.diff(wl)
        if not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
            raise SpectwinInputError(
                "wavelengths_nm: the LUT path (lut_size) needs a regular grid; use "
                "lut_size=None for irregular grids"
            )
        lut = _jakob_lut(size, float(wl[0]), float(wl[-1]), float(steps[0]))
        dimensional = np.reshape(lut.RGB_to_coefficients(colours), (-1, 3))
        poly = dimensional @ np.stack([wl**2, wl, np.ones_like(wl)])
        spectra = 0.5 + poly / (2.0 * np.sqrt(1.0 + poly * poly))
        return spectra[inverse].reshape(*pixels.shape[:-1], grid.size)

    cmfs = colour.MSDS_CMFS[_CMFS_NAME]
    illuminant = colour.SDS_ILLUMINANTS["D65"]
    weights = cmfs[wl] * (illuminant[wl] * np.gradient(wl))[:, None]
    weights /= weights[:, 1].sum()  # a perfect white reflector has Y = 1
    # Like colour's LUT generation: adapt sRGB's D65 white to the white of a perfect reflector
    # integrated on this grid (CAT02), so grey inputs give exactly flat spectra.
    white_xy = colour.XYZ_to_xy(weights.sum(axis=0))
    targets = colour.RGB_to_XYZ(colours, _srgb(), white_xy)
    x = (wl - wl[0]) / (wl[-1] - wl[0])
    basis = np.stack([x**2, x, np.ones_like(x)])
    spectra = np.empty((len(colours), grid.size))
    rows_per_chunk = max(1, _CHUNK_ELEMENTS // (9 * grid.size))
    for start in range(0, len(colours), rows_per_chunk):
        chunk = slice(start, start + rows_per_chunk)
        coefficients = _jakob_fit(targets[chunk], weights, basis)
        spectra[chunk] = _jakob_model(coefficients, basis)[0]
    return spectra[inverse].reshape(*pixels.shape[:-1], grid.size)


def aplus(
    rgb: np.ndarray,
    response: np.ndarray,
    training_spectra: np.ndarray,
    training_rgb: np.ndarray | None = None,
    **options,
) -> np.ndarray:
    """:func:`spectral_a_plus` in the project's ``(rgb, response, ...)`` calling order."""
    return spectral_a_plus(rgb, training_spectra, training_rgb, response=response, **options)


# The short names of the project's stable entry points (ARCHITECTURE.md). Smits and Jakob take
# linear sRGB reflectance and wavelengths, not a camera response.
murakami = murakami_2007
dong = dong_2016
smits = smits_1999
jakob2019 = jakob_2019
