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
- Bad input raises :class:`recon.errors.InputError` naming the argument.

Methods (the thesis compares them with spectralization in chapter 7, Sec. 7.1-7.6, and in
Sec. 10.4.3-10.4.4), one module per method, each registered by its short name in
:data:`RECOVERY_METHODS` and callable by name through :func:`recover` (as colour-science's
``colour.XYZ_to_sd(XYZ, method=...)`` dispatches through ``XYZ_TO_SD_METHODS``):

- ``"imai"``, :func:`imai` (:mod:`~recon.baselines.imai_berns1999`): pseudo-inverse
  :math:`S = V R^+`, the minimal-norm inverse matrix (Sec. 6.1).
- ``"hardeberg"``, :func:`hardeberg` (:mod:`~recon.baselines.hardeberg1999`): the inverse
  matrix trained on known spectra, :math:`W = \\arg\\min \\|V_{known} W - S_{known}\\|^2`
  (Sec. 6.1).
- ``"murakami"``, :func:`murakami_2007` (:mod:`~recon.baselines.murakami2007`): Gaussian-prior
  (Wiener) estimate from the known spectra's statistics plus a spatially interpolated
  correction at the known points (Sec. 5, 7.1).
- ``"dong"``, :func:`dong_2016` (:mod:`~recon.baselines.dong2016`): a non-negative basis of the
  known spectra by NMF, coefficients per pixel from the RGB (Sec. 5, 10.4.3).
- ``"aplus"``, :func:`aplus` and :func:`spectral_a_plus`
  (:mod:`~recon.baselines.aeschbacher2017`): anchored neighbourhood regression on a sparse
  spectral dictionary (Sec. 5, 7.1, 10.4.4; defaults sparsity 8 and :math:`\\lambda = 0.1` as
  quoted in Sec. 7.1). :func:`aplus` takes the project's ``(rgb, response, ...)`` order,
  :func:`spectral_a_plus` the paper's.
- ``"smits"``, :func:`smits_1999` (:mod:`~recon.baselines.smits1999`) and ``"jakob2019"``,
  :func:`jakob_2019` (:mod:`~recon.baselines.jakob_hanika2019`): heuristic RGB-to-reflectance
  upsampling that uses no known spectra (Sec. 7.1); input is linear RGB with sRGB primaries,
  see each function.

The short names ``murakami``, ``dong``, ``smits`` and ``jakob2019`` are the same functions as
``murakami_2007``, ``dong_2016``, ``smits_1999`` and ``jakob_2019``. The modules are named after
the papers as cited (first author, or both of two, and the year), not after the functions, so
that no module hides a function of the same name (``recon.baselines.jakob2019`` is a function).
Shared input checks are in :mod:`recon.baselines.common`.

References
----------
- The thesis, Sec. 6.1 (inverse-matrix methods, Eq. 6.1-6.2), chapter 7 (comparisons). Each
  method's module cites its paper.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from recon.baselines.aeschbacher2017 import aplus, spectral_a_plus
from recon.baselines.dong2016 import dong_2016
from recon.baselines.hardeberg1999 import hardeberg
from recon.baselines.imai_berns1999 import imai
from recon.baselines.jakob_hanika2019 import jakob_2019
from recon.baselines.murakami2007 import murakami_2007
from recon.baselines.smits1999 import smits_1999
from recon.errors import InputError

__all__ = [
    "RECOVERY_METHODS",
    "aplus",
    "dong",
    "dong_2016",
    "hardeberg",
    "imai",
    "jakob2019",
    "jakob_2019",
    "murakami",
    "murakami_2007",
    "recover",
    "smits",
    "smits_1999",
    "spectral_a_plus",
]

# The short names of the project's stable entry points (ARCHITECTURE.md). Smits and Jakob take
# linear sRGB reflectance and wavelengths, not a camera response.
murakami = murakami_2007
dong = dong_2016
smits = smits_1999
jakob2019 = jakob_2019

RECOVERY_METHODS: dict[str, Callable[..., np.ndarray]] = {
    "imai": imai,
    "hardeberg": hardeberg,
    "murakami": murakami,
    "dong": dong,
    "aplus": aplus,
    "smits": smits,
    "jakob2019": jakob2019,
}
"""The spectral recovery methods by their short (lower-case) names, for :func:`recover`.

Each value is the module attribute of the same name (``RECOVERY_METHODS["dong"]`` is
:func:`dong`, that is :func:`dong_2016`)."""


def recover(rgb: np.ndarray, *args: Any, method: str, **kwargs: Any) -> np.ndarray:
    """Spectra from RGB by the spectral recovery method named ``method``.

    Looks the method up in :data:`RECOVERY_METHODS` (case-insensitively) and calls it with
    ``rgb`` and the remaining arguments unchanged, so ``recover(rgb, response, method="imai")``
    is ``imai(rgb, response)``; like ``colour.XYZ_to_sd(XYZ, method=...)`` in colour-science.
    The methods take different arguments after ``rgb``:

    - ``"imai"``: ``response`` (:func:`imai`).
    - ``"hardeberg"``: ``known_spectra, known_pixels`` or ``known_spectra, known_rgb=...``
      (:func:`hardeberg`).
    - ``"murakami"``: ``response, known_spectra, known_pixels`` (:func:`murakami_2007`).
    - ``"dong"``: ``response, known_spectra[, n_components]`` (:func:`dong_2016`).
    - ``"aplus"``: ``response, training_spectra[, training_rgb]`` and the options of
      :func:`spectral_a_plus` (:func:`aplus`).
    - ``"smits"``: ``wavelengths_nm`` (:func:`smits_1999`).
    - ``"jakob2019"``: ``wavelengths_nm[, lut_size=...]`` (:func:`jakob_2019`).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values (linear sRGB in [0, 1] for ``"smits"`` and ``"jakob2019"``).
    *args, **kwargs
        The method's other arguments, as listed above.
    method
        A key of :data:`RECOVERY_METHODS`, in any letter case.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra, exactly what the method returns.

    Raises
    ------
    recon.errors.InputError
        If ``method`` names no registered method (the message lists the valid names), or for
        bad input to the method itself.
    """
    function = RECOVERY_METHODS.get(method.lower()) if isinstance(method, str) else None
    if function is None:
        raise InputError(
            f"method: unknown spectral recovery method {method!r}; expected one of "
            f"{', '.join(RECOVERY_METHODS)}"
        )
    return function(rgb, *args, **kwargs)
