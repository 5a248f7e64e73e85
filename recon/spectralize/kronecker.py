"""Fast exact solver for spectralization energies whose normal equations split as a Kronecker sum.

When every band carries the same data and prior weights (the point-spectra energy, Eq. 6.10,
optionally with the spectral smoothness term of Eq. 10.12), setting the gradient of the energy
to zero gives the Sylvester equation

.. math:: A X + X B = C, \\qquad A = \\alpha P + \\gamma L, \\quad
          B = \\beta R_{cam} R_{cam}^T + \\delta L_s L_s^T,

with :math:`P` the diagonal indicator of measured pixels, :math:`L` the Laplacian of the
appearance-neighbour graph (an ``n x n`` sparse matrix) and :math:`B` a small ``K x K`` matrix.
Diagonalizing :math:`B = Q \\Lambda Q^T` decouples the bands: every column :math:`y_l` of
:math:`Y = X Q` solves the sparse, symmetric positive definite system
:math:`(A + \\lambda_l I) y_l = (C Q)_l`. These are solved by conjugate gradients, preconditioned
with algebraic multigrid (smoothed aggregation, pyamg) where :math:`\\lambda_l` is small next to
the diagonal of :math:`A` and with the diagonal (Jacobi) where it dominates. One multigrid
hierarchy serves all shifts within a factor of two, so only a handful are built.

This replaces the thesis's matrix-free LSQR (section 6.4), which needs hundreds of iterations
because information spreads one graph link per iteration; multigrid moves it across the graph in
one cycle. Columns that share one shift (the :math:`K - 3` metameric-black directions when
:math:`\\delta = 0`) also share the matrix, so their right-hand sides are compressed to their
numerical rank before solving.

References
----------
- The thesis, Eq. 6.10, 6.12, 10.12 and section 11.2 (speed as the method's main drawback).
- Vanek, P., Mandel, J., & Brezina, M. (1996). Algebraic multigrid by smoothed aggregation for
  second and fourth order elliptic problems. Computing, 56(3), 179-196.
- Olson, L. N., & Schroder, J. B. (2018). PyAMG: Algebraic Multigrid Solvers in Python v4.0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyamg
from scipy import sparse
from scipy.sparse import linalg
from threadpoolctl import threadpool_limits

from recon.progress import progress_steps

__all__ = ["KroneckerSolveInfo", "solve_kronecker_sum"]

_JACOBI_SHIFT = 0.05  # shift / mean diagonal of A above which Jacobi preconditioning suffices


@dataclass(frozen=True)
class KroneckerSolveInfo:
    """What the solve did: CG iterations per band column, the shifts :math:`\\lambda_l`,
    multigrid hierarchies built and sparse systems solved (after right-hand-side compression)."""

    iterations: np.ndarray
    shifts: np.ndarray
    hierarchies: int
    solves: int
    converged: bool


def _shift_groups(shifts: np.ndarray, mean_diagonal: float) -> list[tuple[float | None, list]]:
    """Group column indices by preconditioner: ``None`` for Jacobi, else the smallest shift of
    a group whose shifts lie within a factor of two (zero-shifts form their own group)."""
    groups: list[tuple[float | None, list]] = []
    jacobi = [column for column, s in enumerate(shifts) if s >= _JACOBI_SHIFT * mean_diagonal]
    if jacobi:
        groups.append((None, jacobi))
    floor = 1e-12 * max(float(np.max(np.abs(shifts))), mean_diagonal)
    rest = sorted(
        (max(float(s), 0.0), column) for column, s in enumerate(shifts) if column not in jacobi
    )
    for shift, column in rest:
        shift = 0.0 if shift <= floor else shift
        if groups and groups[-1][0] is not None and shift <= 2 * groups[-1][0]:
            groups[-1][1].append(column)
        else:
            groups.append((shift, [column]))
    return groups


def _equal_shifts(shifts: np.ndarray, columns: list) -> list[tuple[float, list]]:
    """Split ``columns`` into runs of numerically equal shifts (clipped at zero)."""
    scale = max(float(np.max(np.abs(shifts))), 1.0)
    runs: list[tuple[float, list]] = []
    for column in sorted(columns, key=lambda c: shifts[c]):
        shift = max(float(shifts[column]), 0.0)
        if runs and abs(shift - runs[-1][0]) <= 1e-9 * scale:
            runs[-1][1].append(column)
        else:
            runs.append((shift, [column]))
    return runs


def _compressed(block: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """Right-hand sides ``block`` (n, c) of one matrix as ``block @ W`` with orthonormal
    ``W`` (c, r): the directions whose singular value exceeds ``rtol`` times the largest.
    The dropped part is below the solver tolerance, so solving ``r`` systems instead of ``c``
    changes nothing measurable; with point spectra the ``K - 3`` metameric-black columns share
    one matrix and their data has the (often low) rank of the measured spectra."""
    gram = block.T @ block
    energies, directions = np.linalg.eigh(gram)
    singular = np.sqrt(np.clip(energies, 0.0, None))
    keep = singular > rtol * max(float(singular.max()), np.finfo(float).tiny)
    weights = directions[:, keep]
    return block @ weights, weights


def _repeatable_hierarchy(matrix: sparse.csr_matrix) -> pyamg.MultilevelSolver:
    """Smoothed-aggregation hierarchy; pyamg draws the start vector of its spectral-radius
    estimate from numpy's global generator, seeded here (and restored) so that results repeat."""
    state = np.random.get_state()  # noqa: NPY002 (pyamg reads the legacy global generator)
    np.random.seed(0)  # noqa: NPY002
    try:
        return pyamg.smoothed_aggregation_solver(matrix, symmetry="symmetric")
    finally:
        np.random.set_state(state)  # noqa: NPY002


def solve_kronecker_sum(
    spatial: sparse.csr_matrix,
    spectral: np.ndarray,
    rhs: np.ndarray,
    *,
    rtol: float = 1e-6,
    max_iterations: int = 500,
    initial: np.ndarray | None = None,
    progress: bool = False,
) -> tuple[np.ndarray, KroneckerSolveInfo]:
    """Solve :math:`A X + X B = C` for symmetric positive (semi-)definite ``A`` and ``B``.

    Parameters
    ----------
    spatial
        :math:`A`, ``(n, n)`` sparse; :math:`A + \\lambda I` must be positive definite for
        every eigenvalue :math:`\\lambda` of :math:`B` (a connected graph with data ensures it).
    spectral
        :math:`B`, ``(K, K)`` symmetric.
    rhs
        :math:`C`, ``(n, K)``.
    rtol
        Relative residual at which each column's conjugate gradients stop.
    max_iterations
        Iteration cap per column.
    initial
        Optional ``(n, K)`` starting guess (a warm start from a neighbouring BTF slice).
    progress
        Show a progress bar over the K columns.

    Returns
    -------
    X : numpy.ndarray
        ``(n, K)`` solution.
    info : KroneckerSolveInfo
    """
    n, bands = rhs.shape
    shifts, basis = np.linalg.eigh(spectral)
    rotated_rhs = rhs @ basis
    rotated = np.zeros_like(rotated_rhs) if initial is None else initial @ basis
    diagonal = spatial.diagonal()
    mean_diagonal = float(np.mean(diagonal))
    identity = sparse.identity(n, format="csr")
    iterations = np.zeros(bands, dtype=int)
    converged, hierarchies, solves = True, 0, 0
    # Single-threaded BLAS: CG's many short dot products slow down badly with thread hand-offs.
    with (
        threadpool_limits(1, user_api="blas"),
        progress_steps("spectralize: band columns", bands, enabled=progress) as advance,
    ):
        for group_shift, columns in _shift_groups(shifts, mean_diagonal):
            if group_shift is None:
                preconditioners = {
                    c: linalg.LinearOperator(
                        (n, n), matvec=lambda v, d=diagonal + shifts[c]: v / d, dtype=np.float64
                    )
                    for c in columns
                }
            else:
                hierarchy = _repeatable_hierarchy((spatial + group_shift * identity).tocsr())
                hierarchies += 1
                preconditioner = hierarchy.aspreconditioner(cycle="V")
                preconditioners = dict.fromkeys(columns, preconditioner)
            for shift, members in _equal_shifts(shifts, columns):
                system = spatial + shift * identity
                block, weights = _compressed(rotated_rhs[:, members], rtol)
                start = rotated[:, members] @ weights
                solved = np.empty_like(block)
                for c in range(block.shape[1]):
                    counter = _Counter()
                    solved[:, c], status = linalg.cg(
                        system,
                        block[:, c],
                        x0=start[:, c],
                        rtol=rtol,
                        maxiter=max_iterations,
                        M=preconditioners[members[0]],
                        callback=counter,
                    )
                    iterations[members] = np.maximum(iterations[members], counter.count)
                    converged &= status == 0
                rotated[:, members] = solved @ weights.T
                solves += block.shape[1]
                for _ in members:
                    advance()
    return rotated @ basis.T, KroneckerSolveInfo(iterations, shifts, hierarchies, solves, converged)


class _Counter:
    """Counts conjugate-gradient iterations through scipy's callback."""

    def __init__(self) -> None:
        self.count = 0

    def __call__(self, _xk) -> None:
        self.count += 1
