"""A multigrid V-cycle that preconditions many right-hand sides at once, in single precision.

The hierarchy is smoothed aggregation's: aggregates of connected unknowns (pyamg's standard
aggregation on the matrix's own pattern, every link counted as strong), tentative prolongators
fitted to the constant vector (on the finest level relaxed first), smoothed by one Jacobi step
weighted with each row's l1 sum, and Galerkin coarse matrices :math:`A_{k+1} = P_k^T A_k P_k`,
all kept in CSR (pyamg's own builder goes through 1 x 1 block matrices, whose absolute value
alone took most of a 7 s setup at one megapixel). The cycle itself is applied here to a whole
block of columns: every level's sparse matrix is read once per sweep for all columns (a
sparse-times-dense product) instead of once per column, and in float32, which halves the memory
traffic. Smoothing is l1-Jacobi (each row scaled by its absolute row sum,
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

from dataclasses import dataclass

import numpy as np
from pyamg.aggregation.aggregate import standard_aggregation
from pyamg.aggregation.tentative import fit_candidates
from pyamg.relaxation.relaxation import gauss_seidel
from scipy import sparse

__all__ = ["BlockVCycle"]

_SWEEPS = 2  # Jacobi sweeps before and after each coarse correction
_COARSEST = 500  # unknowns at which the coarse system is solved densely
_MAX_LEVELS = 10
_OMEGA = 4.0 / 3.0  # damping of the prolongation smoothing step
_CANDIDATE_SWEEPS = 2  # symmetric Gauss-Seidel sweeps on A x = 0 that shape the first candidate


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
        self.levels: list[_Level] = []
        current = sparse.csr_matrix(matrix, dtype=np.float64)
        candidates = _improved_candidate(current)
        while current.shape[0] > _COARSEST and len(self.levels) < _MAX_LEVELS:
            row_sums = np.asarray(abs(current).sum(axis=1)).ravel()  # l1 row sums
            prolongator, candidates = _smoothed_prolongator(current, candidates, row_sums)
            if not 0 < prolongator.shape[1] < current.shape[0]:  # nothing left to aggregate
                break
            restrictor = prolongator.T.tocsr()
            self.levels.append(_single_precision(current, prolongator, restrictor, row_sums))
            current = (restrictor @ (current @ prolongator)).tocsr()
        self.coarse_inverse = np.linalg.pinv(current.toarray(), hermitian=True).astype(np.float32)

    def __call__(self, block: np.ndarray) -> np.ndarray:
        """Approximate :math:`A^{-1}` ``block`` for ``(n, r)`` float64 blocks (returns float64)."""
        return self._cycle(0, np.asarray(block, dtype=np.float32)).astype(np.float64)

    def _cycle(self, depth: int, rhs: np.ndarray) -> np.ndarray:
        if depth == len(self.levels):
            return self.coarse_inverse @ rhs
        level = self.levels[depth]
        x = level.damped_inverse_diagonal * rhs
        _smooth(level, rhs, x, _SWEEPS - 1)
        x += level.prolongator @ self._cycle(depth + 1, level.restrictor @ _residual(level, rhs, x))
        _smooth(level, rhs, x, _SWEEPS)
        return x


def _smooth(level: _Level, rhs: np.ndarray, x: np.ndarray, sweeps: int) -> None:
    """``sweeps`` l1-Jacobi steps on ``x`` in place."""
    for _ in range(sweeps):
        correction = _residual(level, rhs, x)
        correction *= level.damped_inverse_diagonal
        x += correction


def _residual(level: _Level, rhs: np.ndarray, x: np.ndarray) -> np.ndarray:
    """:math:`b - A_k x` in the array of the product (each fresh tall array costs page faults)."""
    residual = level.matrix @ x
    np.subtract(rhs, residual, out=residual)
    return residual


def _improved_candidate(matrix: sparse.csr_matrix) -> np.ndarray:
    """The near-null-space candidate of the finest level, ``(n, 1)``: the constant vector
    relaxed by symmetric Gauss-Seidel on :math:`A x = 0` (pyamg's default candidate
    improvement). Where the data term anchors pixels the constant is far from the null space;
    the relaxed vector dips there, and the tentative prolongator fitted to it cuts the
    conjugate-gradient iterations by a quarter (17 to 13 at one megapixel)."""
    candidate = np.ones(matrix.shape[0])
    gauss_seidel(matrix, candidate, np.zeros_like(candidate), _CANDIDATE_SWEEPS, "symmetric")
    return candidate[:, None]


def _smoothed_prolongator(
    matrix: sparse.csr_matrix, candidates: np.ndarray, row_sums: np.ndarray
) -> tuple[sparse.csr_matrix, np.ndarray]:
    """Smoothed aggregation's prolongator :math:`P = (I - \\omega D_1^{-1} A) T` and the coarse
    near-null-space candidates: aggregates of connected unknowns (pyamg's standard aggregation
    on the matrix's pattern: symmetric strength with threshold 0 keeps every link, so it is
    skipped), the tentative prolongator :math:`T` fitted to the candidates, and one Jacobi step
    weighted row by row with the l1 row sums :math:`D_1` (the Gershgorin bound, so no
    spectral-radius estimate is needed), all in CSR."""
    aggregates, _ = standard_aggregation(matrix)
    tentative, coarse_candidates = fit_candidates(aggregates, candidates)
    tentative = sparse.csr_matrix(tentative)
    update = (matrix @ tentative).tocsr()
    update.data *= np.repeat(_OMEGA / np.where(row_sums > 0, row_sums, 1.0), np.diff(update.indptr))
    return (tentative - update).tocsr(), coarse_candidates


def _single_precision(
    matrix: sparse.csr_matrix,
    prolongator: sparse.csr_matrix,
    restrictor: sparse.csr_matrix,
    row_sums: np.ndarray,
) -> _Level:
    """One level in float32 CSR with its l1-Jacobi scaling :math:`1 / \\sum_j |a_{ij}|`."""
    return _Level(
        sparse.csr_matrix(matrix, dtype=np.float32),
        sparse.csr_matrix(prolongator, dtype=np.float32),
        sparse.csr_matrix(restrictor, dtype=np.float32),
        (1.0 / row_sums[:, None]).astype(np.float32),
    )
