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
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from threadpoolctl import threadpool_limits

from recon.progress import progress_steps
from recon.spectralize.multigrid import BlockVCycle

__all__ = ["FactoredRhs", "KroneckerSolveInfo", "solve_kronecker_sum"]

_JACOBI_SHIFT = 0.05  # shift / mean diagonal of A above which Jacobi preconditioning suffices
_PARTS = 2  # each group's block is iterated in this many column parts, one thread each


@dataclass(frozen=True)
class FactoredRhs:
    """A right-hand side :math:`C = U W + S`, ``(n, K)``, kept in factors: ``left`` :math:`U`
    ``(n, c)`` times ``right`` :math:`W` ``(c, K)`` (the camera term's :math:`f V R_{cam}^T`,
    c = 3 channels) plus ``rows`` :math:`S`, a sparse ``(n, K)`` matrix (the measured spectra at
    their pixels). The solver needs only :math:`C^T C` and :math:`C P` for a few directions
    :math:`P`, which the factors give without forming the ``(n, K)`` array."""

    left: np.ndarray
    right: np.ndarray
    rows: sparse.csr_matrix

    @property
    def shape(self) -> tuple[int, int]:
        return (self.left.shape[0], self.right.shape[1])

    def gram(self) -> np.ndarray:
        """:math:`C^T C`, ``(K, K)``."""
        cross = self.right.T @ np.asarray(self.rows.T @ self.left).T
        rows_gram = (self.rows.T @ self.rows).toarray()
        return self.right.T @ (self.left.T @ self.left) @ self.right + cross + cross.T + rows_gram

    def __matmul__(self, directions: np.ndarray) -> np.ndarray:
        """:math:`C P` for ``directions`` :math:`P`, ``(K, r)``."""
        return self.left @ (self.right @ directions) + self.rows @ directions


@dataclass(frozen=True)
class KroneckerSolveInfo:
    """What the solve did: CG iterations per band column, the shifts :math:`\\lambda_l`,
    multigrid hierarchies built and sparse systems solved (after right-hand-side compression).
    The solution is ``coefficients @ directions.T``: ``directions`` ``(K, r)`` orthonormal, the
    compressed band-space directions of the ``r = solves`` systems, and ``coefficients``
    ``(n, r)`` their solutions."""

    iterations: np.ndarray
    shifts: np.ndarray
    hierarchies: int
    solves: int
    converged: bool
    coefficients: np.ndarray
    directions: np.ndarray


def _shift_groups(shifts: np.ndarray, mean_diagonal: float) -> list[tuple[float | None, list[int]]]:
    """Group column indices by preconditioner: ``None`` for Jacobi, else the smallest shift of
    a group whose shifts lie within a factor of two (zero-shifts form their own group)."""
    groups: list[tuple[float | None, list[int]]] = []
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


def _equal_shifts(shifts: np.ndarray, columns: list[int]) -> list[tuple[float, list[int]]]:
    """Split ``columns`` into runs of numerically equal shifts (clipped at zero)."""
    scale = max(float(np.max(np.abs(shifts))), 1.0)
    runs: list[tuple[float, list[int]]] = []
    for column in sorted(columns, key=lambda c: shifts[c]):
        shift = max(float(shifts[column]), 0.0)
        if runs and abs(shift - runs[-1][0]) <= 1e-9 * scale:
            runs[-1][1].append(column)
        else:
            runs.append((shift, [column]))
    return runs


def _compressed(gram: np.ndarray, rtol: float, floor: float = 0.0) -> np.ndarray:
    """Orthonormal directions ``W`` (c, r) that keep of right-hand sides with Gram matrix
    ``gram`` (c, c) of one matrix the part whose singular value exceeds ``rtol`` times the
    largest, and ``floor``. The dropped part is below the solver tolerance, so solving ``r``
    systems instead of ``c`` changes nothing measurable; with point spectra the ``K - 3``
    metameric-black columns share one matrix and their data has the (often low) rank of the
    measured spectra. ``floor`` drops right-hand sides that the Gram matrix of the whole of
    :math:`C` cannot tell from zero (the camera directions of the regression prior on
    noise-free camera values), of which no relative residual could be asked."""
    energies, directions = np.linalg.eigh(gram)
    singular = np.sqrt(np.clip(energies, 0.0, None))
    threshold = max(rtol * float(singular.max()), floor, np.finfo(float).tiny)
    return directions[:, singular > threshold]


def _column_norms(block: np.ndarray) -> np.ndarray:
    """Euclidean norm of every column of an ``(n, c)`` block (a third of numpy.linalg.norm's
    time on tall blocks)."""
    return np.sqrt(np.einsum("ij,ij->j", block, block))


def _block_cg(
    spatial: sparse.csr_matrix,
    shifts: np.ndarray,
    rhs: np.ndarray,
    start: np.ndarray | None,
    preconditioner: Callable[[np.ndarray, np.ndarray], np.ndarray],
    bound: float,
    max_iterations: int,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Preconditioned conjugate gradients on the columns of ``rhs`` at once: column ``c``
    solves :math:`(A + s_c I) x_c = b_c` until :math:`\\lVert r_c \\rVert \\le` ``bound``.
    ``preconditioner(block, columns)`` approximates the inverse on the given columns; ``start``
    is the first guess (``None``: zero). The Polak-Ribiere form of the step keeps the iteration
    convergent with a preconditioner that is symmetric only up to single-precision rounding.
    Returns the solutions, the iterations per column and whether all converged."""
    iterations = np.zeros(rhs.shape[1], dtype=int)
    shifted = bool(np.any(shifts))
    if start is None:
        solution, residual = np.zeros_like(rhs), rhs.copy()
    else:
        solution = np.array(start, dtype=np.float64)
        residual = rhs - spatial @ solution
        if shifted:
            residual -= solution * shifts
    columns = np.flatnonzero(_column_norms(residual) > bound)
    current, residual = solution[:, columns], residual[:, columns]
    preconditioned = preconditioner(residual, columns)
    direction = preconditioned.copy()
    product = np.einsum("ij,ij->j", residual, preconditioned)
    # Updates run in place (``image`` and ``direction`` hold their step-scaled values), since
    # every fresh (n, c) array costs page faults at a megapixel.
    for _ in range(max_iterations):
        if not columns.size:
            break
        image = spatial @ direction
        if shifted:
            image += direction * shifts[columns]
        step = product / np.einsum("ij,ij->j", direction, image)
        direction *= step
        current += direction
        image *= step
        residual -= image
        iterations[columns] += 1
        active = _column_norms(residual) > bound
        if not active.all():  # retire the converged columns
            solution[:, columns[~active]] = current[:, ~active]
            columns, current, residual = columns[active], current[:, active], residual[:, active]
            image, direction = image[:, active], direction[:, active]
            product, step = product[active], step[active]
        preconditioned = preconditioner(residual, columns)
        following = np.einsum("ij,ij->j", residual, preconditioned)
        # Polak-Ribiere: (r_new - r_old) . z_new / (r_old . z_old), with r_new - r_old = -image.
        beta = np.maximum(-np.einsum("ij,ij->j", image, preconditioned) / product, 0.0)
        direction *= beta / step
        direction += preconditioned
        product = following
    solution[:, columns] = current
    return solution, iterations, not columns.size


class _Jacobi:
    """Diagonal preconditioner of :math:`A + s_c I` for a block's columns, kept for the columns
    still iterating (so that no step gathers the diagonal anew)."""

    def __init__(self, diagonal: np.ndarray, shifts: np.ndarray) -> None:
        self.inverse = 1.0 / (diagonal[:, None] + shifts[None, :])
        self.columns = np.arange(shifts.size)

    def __call__(self, block: np.ndarray, columns: np.ndarray) -> np.ndarray:
        if columns.size != self.columns.size:
            self.inverse = self.inverse[:, np.searchsorted(self.columns, columns)]
            self.columns = columns
        return block * self.inverse


def _solve_part(
    spatial: sparse.csr_matrix,
    block: np.ndarray,
    start: np.ndarray | None,
    shifts: np.ndarray,
    cycle: BlockVCycle | None,
    bound: float,
    max_iterations: int,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """One thread's share of a group: conjugate gradients on the right-hand sides ``block``
    (multigrid ``cycle``, or Jacobi where it is ``None``). Returns the solutions, the iterations
    per column and whether all converged."""
    preconditioner: Callable[[np.ndarray, np.ndarray], np.ndarray]
    if cycle is None:
        preconditioner = _Jacobi(spatial.diagonal(), shifts)
    else:
        preconditioner = lambda r, _c: cycle(r)  # noqa: E731
    return _block_cg(spatial, shifts, block, start, preconditioner, bound, max_iterations)


def solve_kronecker_sum(
    spatial: sparse.csr_matrix,
    spectral: np.ndarray,
    rhs: np.ndarray | FactoredRhs,
    *,
    rtol: float = 1e-6,
    max_iterations: int = 500,
    initial: np.ndarray | None = None,
    rows: np.ndarray | None = None,
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
        :math:`C`, ``(n, K)``: an array, or :class:`FactoredRhs`.
    rtol
        Relative residual :math:`\\lVert R \\rVert_F / \\lVert C_g \\rVert_F` to reach in each
        group :math:`g` of columns that share one preconditioner (after compression), shared
        equally among them: a column stops once its residual is below ``rtol``
        :math:`\\lVert C_g \\rVert_F / \\sqrt{n_g}`. This bounds the energy error
        :math:`\\sum_l r_l^T (A + \\lambda_l I)^{-1} r_l` as a relative residual of ``rtol`` in
        every column would, but columns with little data (the directions of measurement noise
        on the known spectra) stop after a few steps.
    max_iterations
        Iteration cap per column.
    initial
        Optional ``(n, K)`` starting guess (a warm start from a neighbouring BTF slice).
    rows
        Optional indices of the rows of :math:`X` to return (the held-out pixels of a
        cross-validation fold); ``None``: all ``n``. The solve is the same; only the
        assembly of :math:`X` from ``info.coefficients`` is restricted to them.
    progress
        Show a progress bar over the K columns.

    Returns
    -------
    X : numpy.ndarray
        ``(n, K)`` solution, or its ``rows``.
    info : KroneckerSolveInfo
    """
    shifts, basis = np.linalg.eigh(spectral)
    # Each run of equal shifts is solved on its compressed directions, columns of a
    # ``projection`` (K, r) in band space; the Gram matrix of C serves the compression and the
    # stopping bounds. C is projected once onto all groups' directions, and the solution
    # assembled once from all of them: passes over (n, K) arrays cost more than a CG step.
    gram = rhs.gram() if isinstance(rhs, FactoredRhs) else rhs.T @ rhs
    rotated_gram = basis.T @ gram @ basis
    mean_diagonal = float(np.mean(spatial.diagonal()))
    # What the Gram matrix cannot tell from zero: its entries carry rounding errors of about
    # eps |C|_F^2, so singular values below about sqrt(eps) |C|_F are noise.
    rounding_floor = 10 * np.sqrt(np.finfo(float).eps * max(float(np.trace(gram)), 0.0))
    groups = []
    for group_shift, members in _shift_groups(shifts, mean_diagonal):
        # One block per group: each run of equal shifts compressed to its numerical rank.
        runs = []
        for _, run in _equal_shifts(shifts, members):
            weights = _compressed(rotated_gram[np.ix_(run, run)], rtol, rounding_floor)
            runs.append((run, weights.shape[1], basis[:, run] @ weights))
        projection = np.hstack([projection for _, _, projection in runs])
        if projection.shape[1] == 0:  # no right-hand side in this group: its columns are zero
            continue
        block_shifts = np.concatenate(
            [np.full(width, max(shifts[run[0]], 0.0)) for run, width, _ in runs]
        )
        # The group's relative residual, shared equally among its columns.
        block_energy = float(np.einsum("kr,kl,lr->", projection, gram, projection))
        bound = rtol * np.sqrt(max(block_energy, 0.0) / projection.shape[1])
        groups.append((group_shift, members, runs, projection, block_shifts, bound))
    projection = np.hstack([group[3] for group in groups])
    projected = rhs @ projection
    started = None if initial is None else initial @ projection
    solved = np.empty_like(projected)
    iterations = np.zeros(rhs.shape[1], dtype=int)
    hierarchies, offset, pending = 0, 0, []
    # Single-threaded BLAS: CG's many short dot products slow down badly with thread hand-offs.
    with (
        threadpool_limits(1, user_api="blas"),
        progress_steps("spectralize: band columns", rhs.shape[1], enabled=progress) as advance,
        ThreadPoolExecutor(_PARTS) as pool,
    ):
        # Jacobi groups come first, so that they iterate while the hierarchies are built.
        for group_shift, members, runs, group_projection, block_shifts, bound in groups:
            cycle = None
            if group_shift is not None:
                cycle = BlockVCycle(
                    (spatial + group_shift * sparse.identity(spatial.shape[0])).tocsr()
                )
                hierarchies += 1
            # Dealt out back and forth (0 1 1 0 0 1 ...) over the columns, which come in
            # ascending order of data: the parts get large and small right-hand sides alike.
            width = group_projection.shape[1]
            turn = np.arange(width) % (2 * _PARTS)
            owner = np.minimum(turn, 2 * _PARTS - 1 - turn)
            parts = [offset + np.flatnonzero(owner == i) for i in range(min(_PARTS, width))]
            futures = [
                pool.submit(
                    _solve_part,
                    spatial,
                    projected[:, part],
                    None if started is None else started[:, part],
                    block_shifts[part - offset],
                    cycle,
                    bound,
                    max_iterations,
                )
                for part in parts
            ]
            pending.append((runs, parts, futures, len(members), offset))
            offset += width
        converged = True
        for runs, parts, futures, count, first in pending:
            counts = np.empty(projected.shape[1], dtype=int)
            for part, future in zip(parts, futures, strict=True):
                solved[:, part], counts[part], done = future.result()
                converged &= done
            for run, width, _ in runs:
                iterations[run] = counts[first : first + width].max(initial=0)
                first += width
            advance(count)
    solution = (solved if rows is None else solved[rows]) @ projection.T
    return solution, KroneckerSolveInfo(
        iterations, shifts, hierarchies, projection.shape[1], converged, solved, projection
    )
