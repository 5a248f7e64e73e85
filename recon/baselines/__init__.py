"""Spectral recovery methods that compete with spectralization: array in, array out.

Every method recovers spectra from RGB (or any ``C``-channel broadband) data. Conventions:

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
Sec. 10.4.3-10.4.4), one module per method, each with one public function of the method's name,
registered under that name in :data:`RECOVERY_METHODS` and callable by name through
:func:`recover` (as colour-science's ``colour.XYZ_to_sd(XYZ, method=...)`` dispatches through
``XYZ_TO_SD_METHODS``):

- :func:`imai` (:mod:`~recon.baselines.imai_berns1999`): pseudo-inverse :math:`S = V R^+`, the
  minimal-norm inverse matrix (Sec. 6.1).
- :func:`hardeberg` (:mod:`~recon.baselines.hardeberg1999`): the inverse matrix trained on known
  spectra, :math:`W = \\arg\\min \\|V_{known} W - S_{known}\\|^2` (Sec. 6.1).
- :func:`murakami` (:mod:`~recon.baselines.murakami2007`): Gaussian-prior (Wiener) estimate from
  the known spectra's statistics plus a spatially interpolated correction at the known points
  (Sec. 5, 7.1).
- :func:`dong` (:mod:`~recon.baselines.dong2016`): a non-negative basis of the known spectra by
  NMF, coefficients per pixel from the RGB (Sec. 5, 10.4.3).
- :func:`a_plus` (:mod:`~recon.baselines.aeschbacher2017`): Spectral A+, anchored neighbourhood
  regression on a sparse spectral dictionary (Sec. 5, 7.1, 10.4.4; defaults sparsity 8 and
  :math:`\\lambda = 0.1` as quoted in Sec. 7.1).
- :func:`smits` (:mod:`~recon.baselines.smits1999`) and :func:`jakob`
  (:mod:`~recon.baselines.jakob_hanika2019`): heuristic RGB-to-reflectance upsampling that uses
  no known spectra (Sec. 7.1); input is linear RGB with sRGB primaries, see each function.

Every function takes ``rgb`` first, then ``response`` if the method uses one, and everything
else by keyword, with the same names as :func:`recover` (``known_spectra``, ``known_pixels``,
``known_rgb``, then the method's options). The modules are named after the papers as cited
(first author, or both of two, and the year). Shared input checks are in
:mod:`recon.baselines.common`.

References
----------
- The thesis, Sec. 6.1 (inverse-matrix methods, Eq. 6.1-6.2), chapter 7 (comparisons). Each
  method's module cites its paper.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np

from recon.baselines.aeschbacher2017 import a_plus
from recon.baselines.dong2016 import dong
from recon.baselines.hardeberg1999 import hardeberg
from recon.baselines.imai_berns1999 import imai
from recon.baselines.jakob_hanika2019 import jakob
from recon.baselines.murakami2007 import murakami
from recon.baselines.smits1999 import smits
from recon.errors import InputError

__all__ = [
    "RECOVERY_METHODS",
    "a_plus",
    "dong",
    "hardeberg",
    "imai",
    "jakob",
    "murakami",
    "recover",
    "smits",
]

RECOVERY_METHODS: dict[str, Callable[..., np.ndarray]] = {
    "imai": imai,
    "hardeberg": hardeberg,
    "murakami": murakami,
    "dong": dong,
    "a_plus": a_plus,
    "smits": smits,
    "jakob": jakob,
}
"""The spectral recovery methods by their names, for :func:`recover`.

Each key is the name of its function (``RECOVERY_METHODS["dong"]`` is :func:`dong`). A function's
signature says what the method takes: ``response`` as its second parameter if it uses one (with
a default of ``None`` if it can do without), ``known_spectra`` and ``known_pixels`` among its
keyword-only parameters if it uses them, and its options as the other keyword-only parameters;
a keyword-only parameter without a default is required."""


def recover(
    rgb: np.ndarray,
    response: np.ndarray | None,
    *,
    method: str,
    known_pixels: np.ndarray | None = None,
    known_spectra: np.ndarray | None = None,
    **options: Any,
) -> np.ndarray:
    """Spectra from RGB by the spectral recovery method named ``method``.

    Looks the method up in :data:`RECOVERY_METHODS` (case-insensitively), checks that the call
    gives it exactly what it uses, and calls its function: ``recover(rgb, response,
    method="dong", known_spectra=s)`` is ``dong(rgb, response, known_spectra=s)``. What each
    method uses (``response`` ``None`` where it uses none):

    - ``"imai"``: ``response`` (:func:`imai`; thesis Sec. 6.1, Eq. 6.1-6.2). No known spectra.
    - ``"hardeberg"``: ``known_spectra`` with ``known_pixels`` or the option ``known_rgb``; no
      response (:func:`hardeberg`; Sec. 6.1).
    - ``"murakami"``: ``response``, ``known_spectra`` and ``known_pixels`` of an ``(H, W, C)``
      image; options ``correlation_length``, ``rgb_noise_std``, ``nugget``
      (:func:`murakami`; Sec. 7.1).
    - ``"dong"``: ``response`` and ``known_spectra``; options ``n_components``,
      ``random_state``, ``max_iter``, ``tol`` (:func:`dong`; Sec. 10.4.3).
    - ``"a_plus"``: ``known_spectra`` with ``known_pixels``, the option ``known_rgb`` or only
      a ``response``; ``response`` may be ``None`` (estimated from the known pairs); options
      ``known_rgb``, ``n_atoms``, ``sparsity``, ``ridge_lambda``, ``neighbourhood_size``,
      ``n_iter``, ``random_state`` (:func:`a_plus`; Sec. 7.1, 10.4.4).
    - ``"smits"``: linear sRGB ``rgb`` in [0, 1] and the required option ``wavelengths_nm``;
      no response, no known spectra (:func:`smits`; Sec. 7.1).
    - ``"jakob"``: as ``"smits"``, and the option ``lut_size`` (:func:`jakob`; Sec. 7.1).

    The thesis compares these methods with spectralization in chapter 7.

    Parameters
    ----------
    rgb
        ``(..., C)`` device values (linear sRGB in [0, 1] for ``"smits"`` and ``"jakob"``).
    response
        ``(K, C)`` projection with ``rgb = spectra @ response`` (Eq. 6.2), or ``None`` for a
        method that uses none (or, for ``"a_plus"``, to estimate it).
    method
        A key of :data:`RECOVERY_METHODS`, in any letter case.
    known_pixels
        Flat row-major indices into ``rgb.shape[:-1]`` of the known spectra, for the methods
        that use them.
    known_spectra
        ``(m, K)`` known (training) spectra, for the methods that use them.
    **options
        The method's keyword-only options, as listed above.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra, exactly what the method's function returns.

    Raises
    ------
    recon.errors.InputError
        If ``method`` names no registered method (the message lists the valid names), an
        option is not one of the method's (the message lists its options), the method needs
        ``response``, ``known_spectra``, ``known_pixels`` or a required option that is missing,
        or is given one it does not use; or for bad input to the method itself.

    Examples
    --------
    >>> import numpy as np
    >>> rgb, response = np.array([[0.2, 0.4, 0.6]]), np.eye(3)  # K = C = 3
    >>> recover(rgb, response, method="imai").round(12).tolist()
    [[0.2, 0.4, 0.6]]
    >>> recover(rgb, response, method="dong", known_spectra=np.eye(3), max_iter=500).shape
    (1, 3)
    """
    function = RECOVERY_METHODS.get(method.lower()) if isinstance(method, str) else None
    if function is None:
        raise InputError(
            f"method: unknown spectral recovery method {method!r}; expected one of "
            f"{', '.join(RECOVERY_METHODS)}"
        )
    name = method.lower()
    parameters = inspect.signature(function).parameters
    keywords = [p for p in parameters.values() if p.kind is inspect.Parameter.KEYWORD_ONLY]
    valid_options = [p.name for p in keywords if p.name not in ("known_pixels", "known_spectra")]
    unknown = sorted(set(options) - set(valid_options))
    if unknown:
        raise InputError(
            f"options: method {name!r} has no option {', '.join(unknown)}; its options are "
            f"{', '.join(valid_options) if valid_options else 'none'}"
        )
    data = {"known_pixels": known_pixels, "known_spectra": known_spectra}
    given = {key: value for key, value in data.items() if value is not None}
    for key in given:
        if key not in parameters:
            raise InputError(f"{key}: method {name!r} does not use {key}; pass None")
    uses_response = "response" in parameters
    if response is not None and not uses_response:
        raise InputError(f"response: method {name!r} uses no response; pass None")
    if response is None and uses_response and parameters["response"].default is not None:
        raise InputError(
            f"response: method {name!r} needs the (K, C) response with rgb = spectra @ response"
        )
    missing = [
        p.name
        for p in keywords
        if p.default is inspect.Parameter.empty and p.name not in given and p.name not in options
    ]
    if missing:
        raise InputError(f"{missing[0]}: method {name!r} needs {' and '.join(missing)}")
    leading = (rgb, response) if uses_response else (rgb,)
    return function(*leading, **given, **options)
