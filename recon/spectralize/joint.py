"""Both appearance priors of Eq. 6.3 reconstructed together, in one Kronecker solve.

The plain prior and the regression prior (``prior="regression"`` of
:func:`recon.spectralize.solve.build_problem`) give the same normal matrices of Eq. 6.10:
:math:`A = \\alpha P + \\gamma L` over the pixels and :math:`B = \\beta R_{cam} R_{cam}^T` over
the bands; they differ only in the right-hand side :math:`C` (the regression prior solves for
:math:`X - B_{reg}`). Side by side, :math:`A [X_1\\, X_2] + [X_1\\, X_2]\\,
\\mathrm{diag}(B, B) = [C_1\\, C_2]` is one Kronecker sum with ``2 K`` columns: one set of
multigrid hierarchies and one run of block conjugate gradients serve both priors
(:mod:`recon.spectralize.kronecker`), and one assembly of the energy (neighbour links,
Laplacian, terms) serves both (:func:`recon.spectralize.solve.regression_prior`), which is what
makes the cross-validation of :func:`recon.spectralize.choose_prior` cheap. Energies that do not
split as a Kronecker sum are solved one prior at a time.

References
----------
- The thesis, Eq. 6.3, 6.10 and 6.12.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import linalg as dense_linalg
from scipy import sparse

from recon.errors import InputError
from recon.spectralize.kronecker import FactoredRhs, solve_kronecker_sum
from recon.spectralize.solve import (
    PRIORS,
    SpectralizationProblem,
    build_problem,
    reconstruct,
    regression_prior,
)

__all__ = ["reconstruct_priors"]


def _spectra(
    problem: SpectralizationProblem, scaled: np.ndarray, rows: slice | np.ndarray
) -> np.ndarray:
    """The spectra of the scaled unknowns :math:`X` at the pixels ``rows`` (Eq. 10.2 undone)."""
    if problem.base is not None:
        scaled = scaled + problem.base[rows]
    if np.any(problem.scale != 1.0):
        scaled = scaled / problem.scale[rows, None]
    return scaled


def reconstruct_priors(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    priors: Sequence[str] = PRIORS,
    at_pixels: np.ndarray | None = None,
    tol: float = 1e-6,
    max_iterations: int = 500,
    **energy: Any,
) -> dict[str, np.ndarray]:
    """Reconstruct the spectral image once with each prior, solving them jointly.

    Parameters
    ----------
    rgb, response
        As in :func:`recon.spectralize.solve.reconstruct`.
    priors
        The priors to reconstruct with (distinct names of
        :data:`recon.spectralize.solve.PRIORS`).
    at_pixels
        Optional flat pixel indices (over the leading shape of ``rgb``) at which to return the
        spectra: the held-out spots of a fold of :func:`recon.spectralize.choose_prior`, which
        needs no other pixel. The solve is the same; the spectra of the other pixels are not
        assembled from it.
    tol, max_iterations
        As in :func:`~recon.spectralize.solve.reconstruct` (the joint solve's tolerance holds
        for the columns of both priors together).
    **energy
        The energy of :func:`~recon.spectralize.solve.build_problem` (``point_spectra``,
        ``weights``, ``appearance``, ``graph``, ...) except ``prior``; ``neutral`` and
        ``regression`` apply to the regression prior. It is assembled once for all priors
        (:func:`~recon.spectralize.solve.regression_prior`).

    Returns
    -------
    dict
        Per prior, the spectra with the leading shape of ``rgb`` and ``K`` bands, or ``(m, K)``
        at the ``m`` pixels ``at_pixels``.

    Examples
    --------
    >>> import numpy as np
    >>> from recon.spectralize.solve import PointSpectra
    >>> rng = np.random.default_rng(0)
    >>> response, truth = rng.random((8, 3)), rng.random((10, 10, 8))
    >>> known = PointSpectra(np.arange(0, 100, 9), truth.reshape(100, 8)[::9])
    >>> jointly = reconstruct_priors(truth @ response, response, point_spectra=known, tol=1e-10)
    >>> alone = reconstruct(truth @ response, response, point_spectra=known, prior="regression",
    ...                     tol=1e-10)
    >>> bool(np.allclose(jointly["regression"], alone.spectra, atol=1e-6))
    True
    """
    if "prior" in energy:
        raise InputError("prior: reconstruct_priors takes the priors as priors=[...]")
    unknown = [prior for prior in priors if prior not in PRIORS]
    if unknown or len(set(priors)) != len(priors) or not priors:
        raise InputError(f"priors: expected distinct names among {PRIORS}, got {list(priors)}")
    shape = tuple(np.shape(rgb)[:-1])
    pixels = None if at_pixels is None else np.asarray(at_pixels)
    rows = slice(None) if pixels is None else pixels

    def shaped(spectra: np.ndarray) -> np.ndarray:
        """Spectra at ``rows``, ``(m, K)``, with the leading shape of ``rgb`` if all pixels."""
        return spectra.reshape(*shape, -1) if pixels is None else spectra

    regression_options = {
        key: energy.pop(key) for key in ("neutral", "regression") if key in energy
    }
    plain = build_problem(rgb, response, **energy)
    problems = [
        plain if prior == "spectra" else regression_prior(plain, **regression_options)
        for prior in priors
    ]
    parts = [problem.kronecker_parts() for problem in problems]
    if any(part is None for part in parts):
        return {
            prior: shaped(
                reconstruct(
                    rgb,
                    response,
                    prior=prior,
                    tol=tol,
                    max_iterations=max_iterations,
                    **energy,
                    **(regression_options if prior == "regression" else {}),
                ).spectra.reshape(problems[0].n_pixels, -1)[rows]
            )
            for prior in priors
        }
    solved = [part for part in parts if part is not None]
    spatial, spectral, _ = solved[0]
    rhs = FactoredRhs(
        np.hstack([part[2].left for part in solved]),
        dense_linalg.block_diag(*(part[2].right for part in solved)),
        sparse.hstack([part[2].rows for part in solved], format="csr"),
    )
    joint, _ = solve_kronecker_sum(
        spatial,
        dense_linalg.block_diag(*(spectral for _ in solved)),
        rhs,
        rtol=tol,
        max_iterations=max_iterations,
        rows=pixels,
    )
    bands = problems[0].n_bands
    return {
        prior: shaped(_spectra(problem, joint[:, index * bands : (index + 1) * bands], rows))
        for index, (prior, problem) in enumerate(zip(priors, problems, strict=True))
    }
