"""A multigrid V-cycle that preconditions many right-hand sides at once, in single precision.

The hierarchy (aggregates, smoothed prolongators :math:`P_k`, Galerkin coarse matrices
:math:`A_{k+1} = P_k^T A_k P_k`) comes from pyamg's smoothed aggregation. The cycle itself is
applied here to a whole block of columns: every level's sparse matrix is read once per sweep for
all columns (a sparse-times-dense product) instead of once per column, and in float32, which
halves the memory traffic. Smoothing is l1-Jacobi (each row scaled by its absolute row sum,
convergent without a spectral-radius estimate), the same sweeps before and after the coarse
correction, so the cycle is a symmetric operator (as conjugate gradients need); its
single-precision rounding is absorbed by the flexible conjugate gradients of
:mod:`recon.spectralize.kronecker`.

References
----------
- Vanek, P., Mandel, J., & Brezina, M. (1996). Algebraic multigrid by smoothed aggregation for
  second and fourth order elliptic problems. Computing, 56(3), 179-196.
- Baker, A. H., Falgout, R. D., Kolev, T. V., & Yang, U. M. (2011). Multigrid smoothers for
  ultraparallel computing. SIAM J. Sci. Comput. 33(5), 2864-2887 (l1-Jacobi).
- Olson, L. N., & Schroder, J. B. (2018). PyAMG: Algebraic Multigrid Solvers in Python v4.0.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import pyamg
from scipy import sparse

__all__ = ["BlockVCycle"]

_SWEEPS = 2  # Jacobi sweeps before and after each coarse correction
_COARSEST = 500  # unknowns at which the coarse system is solved densely


@dataclass(frozen=True)
class _Level:
    matrix: sparse.csr_matrix  # A_k, float32
    prolongator: sparse.csr_matrix  # P_k, float32
    restrictor: sparse.csr_matrix  # P_k^T, float32
    damped_inverse_diagonal: np.ndarray  # 1 / l1 row sums of A_k, (n_k, 1) float32


class BlockVCycle:
    """Smoothed-aggregation V-cycle applied to ``(n, r)`` blocks of right-hand sides.

    Parameters
    ----------
    matrix
        Symmetric positive definite ``(n, n)`` sparse matrix.
    """

    def __init__(self, matrix: sparse.csr_matrix) -> None:
        with _seeded():
            hierarchy = pyamg.smoothed_aggregation_solver(
                matrix,
                symmetry="symmetric",
                smooth=("jacobi", {"weighting": "local"}),  # no spectral-radius estimates
                max_coarse=_COARSEST,
                improve_candidates=None,
            )
            self.levels = [_smoothed_level(level) for level in hierarchy.levels[:-1]]
        coarse = np.asarray(hierarchy.levels[-1].A.toarray(), dtype=np.float64)
        self.coarse_inverse = np.linalg.pinv(coarse, hermitian=True).astype(np.float32)

    def __call__(self, block: np.ndarray) -> np.ndarray:
        """Approximate :math:`A^{-1}` ``block`` for ``(n, r)`` float64 blocks (returns float64)."""
        return self._cycle(0, np.asarray(block, dtype=np.float32)).astype(np.float64)

    def _cycle(self, depth: int, rhs: np.ndarray) -> np.ndarray:
        if depth == len(self.levels):
            return self.coarse_inverse @ rhs
        level = self.levels[depth]
        x = level.damped_inverse_diagonal * rhs
        for _ in range(_SWEEPS - 1):
            x += level.damped_inverse_diagonal * (rhs - level.matrix @ x)
        x += level.prolongator @ self._cycle(depth + 1, level.restrictor @ (rhs - level.matrix @ x))
        for _ in range(_SWEEPS):
            x += level.damped_inverse_diagonal * (rhs - level.matrix @ x)
        return x


def _smoothed_level(level) -> _Level:
    """One pyamg level in float32 CSR with its l1-Jacobi scaling :math:`1 / \\sum_j |a_{ij}|`."""
    matrix = sparse.csr_matrix(level.A, dtype=np.float32)
    prolongator = sparse.csr_matrix(level.P, dtype=np.float32)
    row_sums = np.asarray(abs(matrix).sum(axis=1), dtype=np.float32)
    return _Level(matrix, prolongator, prolongator.T.tocsr(), 1.0 / row_sums)


@contextmanager
def _seeded():
    """pyamg draws start vectors (spectral-radius estimates) from numpy's global generator:
    seed it (and restore it after) so that results repeat."""
    state = np.random.get_state()  # noqa: NPY002 (pyamg reads the legacy global generator)
    np.random.seed(0)  # noqa: NPY002
    try:
        yield
    finally:
        np.random.set_state(state)  # noqa: NPY002
