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
hierarchy serves all shifts within a factor of two, so only a handful are built, and the columns
it serves are iterated together as one block (:mod:`recon.spectralize.multigrid`): each sparse
matrix is read once per step for all of them, and the V-cycle runs in single precision.

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

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from threadpoolctl import threadpool_limits

from recon.progress import progress_steps
from recon.spectralize.multigrid import BlockVCycle

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


def _block_cg(
    spatial: sparse.csr_matrix,
    shifts: np.ndarray,
    rhs: np.ndarray,
    start: np.ndarray,
    preconditioner: Callable[[np.ndarray, np.ndarray], np.ndarray],
    rtol: float,
    max_iterations: int,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Preconditioned conjugate gradients on the columns of ``rhs`` at once: column ``c``
    solves :math:`(A + s_c I) x_c = b_c` until :math:`\\lVert r_c \\rVert \\le`
    ``rtol`` :math:`\\lVert b_c \\rVert`. ``preconditioner(block, columns)`` approximates the
    inverse on the given columns. The Polak-Ribiere form of the step keeps the iteration
    convergent with a preconditioner that is symmetric only up to single-precision rounding.
    Returns the solutions, the iterations per column and whether all converged."""
    solution = np.array(start, dtype=np.float64)
    iterations = np.zeros(rhs.shape[1], dtype=int)
    bounds = rtol * np.linalg.norm(rhs, axis=0)
    residual = rhs - (spatial @ solution + solution * shifts)
    columns = np.flatnonzero(np.linalg.norm(residual, axis=0) > bounds)
    current, residual = solution[:, columns], residual[:, columns]
    direction = preconditioned = preconditioner(residual, columns)
    product = np.einsum("ij,ij->j", residual, preconditioned)
    for _ in range(max_iterations):
        if not columns.size:
            break
        image = spatial @ direction
        image += direction * shifts[columns]
        step = product / np.einsum("ij,ij->j", direction, image)
        current += step * direction
        previous = residual
        residual = residual - step * image
        iterations[columns] += 1
        active = np.linalg.norm(residual, axis=0) > bounds[columns]
        if not active.all():  # retire the converged columns
            solution[:, columns[~active]] = current[:, ~active]
            columns, current, residual = columns[active], current[:, active], residual[:, active]
            previous, direction, product = (
                previous[:, active],
                direction[:, active],
                product[active],
            )
        preconditioned = preconditioner(residual, columns)
        following = np.einsum("ij,ij->j", residual, preconditioned)
        beta = (following - np.einsum("ij,ij->j", previous, preconditioned)) / product
        direction = preconditioned + np.maximum(beta, 0.0) * direction
        product = following
    solution[:, columns] = current
    return solution, iterations, not columns.size


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
    shifts, basis = np.linalg.eigh(spectral)
    rotated_rhs = rhs @ basis
    rotated = np.zeros_like(rotated_rhs) if initial is None else initial @ basis
    diagonal = spatial.diagonal()
    iterations = np.zeros(rhs.shape[1], dtype=int)
    converged, hierarchies, solves = True, 0, 0
    # Single-threaded BLAS: CG's many short dot products slow down badly with thread hand-offs.
    with (
        threadpool_limits(1, user_api="blas"),
        progress_steps("spectralize: band columns", rhs.shape[1], enabled=progress) as advance,
    ):
        for group_shift, members in _shift_groups(shifts, float(np.mean(diagonal))):
            # One block per group: each run of equal shifts compressed to its numerical rank.
            runs = [
                (run, *_compressed(rotated_rhs[:, run], rtol))
                for _, run in _equal_shifts(shifts, members)
            ]
            block = np.hstack([compressed for _, compressed, _ in runs])
            start = np.hstack([rotated[:, run] @ weights for run, _, weights in runs])
            block_shifts = np.concatenate(
                [np.full(w.shape[1], max(shifts[run[0]], 0.0)) for run, _, w in runs]
            )
            if group_shift is None:
                jacobi = diagonal[:, None] + block_shifts[None, :]
                preconditioner = lambda r, c, d=jacobi: r / d[:, c]  # noqa: E731
            else:
                cycle = BlockVCycle(
                    (spatial + group_shift * sparse.identity(len(diagonal))).tocsr()
                )
                preconditioner = lambda r, _c, m=cycle: m(r)  # noqa: E731
                hierarchies += 1
            solved, counts, done = _block_cg(
                spatial,
                block_shifts,
                block,
                start,
                preconditioner,
                rtol,
                max_iterations,
            )
            converged &= done
            offset = 0
            for run, _, weights in runs:
                width = weights.shape[1]
                rotated[:, run] = solved[:, offset : offset + width] @ weights.T
                iterations[run] = counts[offset : offset + width].max(initial=0)
                offset += width
            solves += block.shape[1]
            advance(len(members))
    return rotated @ basis.T, KroneckerSolveInfo(iterations, shifts, hierarchies, solves, converged)
