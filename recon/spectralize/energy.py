"""The least-squares terms of the spectralization energies (thesis Eq. 6.9, 6.10, 10.1, 10.12).

Each term is linear in the unknown (scaled) spectral image :math:`X`, an ``(n_pixels, K)`` array
with :math:`X_i = f_i S_i` (Eq. 10.2; :math:`f_i = 1` without dynamic-range compression), and
contributes :math:`w \\lVert \\mathcal{A}(X) - b \\rVert^2` to the energy. A term knows its
residual operator :math:`\\mathcal{A}` (``apply``), the adjoint (``adjoint``), its target
:math:`b` and its number of scalar rows (for the weight normalization of Eq. 6.11/10.13). Weights
are applied by :mod:`recon.spectralize.solve`, which stacks the terms into the matrix :math:`M_E` of
Eq. 6.12.

References
----------
- The thesis, Eq. 6.3, 6.9, 6.10 (section 6.3), Eq. 10.1 and 10.12 (section 10.1).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import ndimage, sparse

from recon.spectralize.appearance import NeighbourGraph

__all__ = [
    "AppearancePriorTerm",
    "CameraTerm",
    "DeviceIntegralTerm",
    "FilteredBandTerm",
    "PointSpectraTerm",
    "SpectralSmoothnessTerm",
    "gaussian_plane",
]


def gaussian_plane(plane: np.ndarray, sigma_px: float) -> np.ndarray:
    """The filter :math:`F` of Eq. 10.1: a Gaussian of ``sigma_px`` truncated at 3 sigma with
    zero padding (so its matrix is symmetric and it is its own adjoint); 0 leaves the plane."""
    return ndimage.gaussian_filter(plane, sigma_px, mode="constant", truncate=3.0)


@dataclass(frozen=True)
class PointSpectraTerm:
    """:math:`\\sum_j \\lVert X_{P(j)} - f_{P(j)} D_j \\rVert^2` (Eq. 6.10, first term)."""

    pixels: np.ndarray
    target: np.ndarray  # (m, K): f-scaled measured spectra

    @property
    def n_rows(self) -> int:
        return int(self.target.size)

    def apply(self, x: np.ndarray) -> np.ndarray:
        return x[self.pixels]

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        np.add.at(out, self.pixels, residual)


@dataclass(frozen=True)
class DeviceIntegralTerm:
    """:math:`\\sum_j \\alpha_j \\lVert \\sum_{i,l} w_{i,l,j} X_{i,l} - D_j \\rVert^2`
    (Eq. 6.9, first term): any device reading as a weighted integral over the image cube.

    ``weights`` is an ``(m, n_pixels * K)`` sparse matrix over the row-major flattened cube with
    :math:`\\sqrt{\\alpha_j / \\alpha}` folded into its rows (and into ``target``).
    """

    weights: sparse.csr_matrix
    target: np.ndarray  # (m,)

    @property
    def n_rows(self) -> int:
        return int(self.target.size)

    def apply(self, x: np.ndarray) -> np.ndarray:
        return self.weights @ x.ravel()

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        out += (self.weights.T @ residual).reshape(out.shape)


@dataclass(frozen=True)
class FilteredBandTerm:
    """:math:`\\lVert F * (W X_{:,b}) - F * (W f D^{b}) \\rVert^2` over one image (Eq. 10.1,
    first term): a Gaussian filter :math:`F` of standard deviation ``sigma_px`` applied to band
    ``band`` of image ``image``, each pixel weighed by ``weight`` (:math:`W`, ``None``: the
    thesis's uniform weight) before the filter, so that a pixel of weight 0 enters no filtered
    value. Zero padding keeps the filter matrix symmetric, so it is its own adjoint.
    """

    image: int
    band: int
    sigma_px: float
    shape: tuple[int, int]  # (height, width) of every image
    target: np.ndarray  # (height, width): F * (W f D^b), precomputed as the thesis suggests
    weight: np.ndarray | None = None  # (height, width), or None for 1 everywhere

    @property
    def n_rows(self) -> int:
        return int(self.target.size)

    def pixel_slice(self) -> slice:
        """The flat pixel range of this term's image."""
        size = self.shape[0] * self.shape[1]
        return slice(self.image * size, (self.image + 1) * size)

    def apply(self, x: np.ndarray) -> np.ndarray:
        plane = x[self.pixel_slice(), self.band].reshape(self.shape)
        return gaussian_plane(plane if self.weight is None else self.weight * plane, self.sigma_px)

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        plane = gaussian_plane(residual.reshape(self.shape), self.sigma_px)
        if self.weight is not None:
            plane = self.weight * plane
        out[self.pixel_slice(), self.band] += plane.ravel()


@dataclass(frozen=True)
class CameraTerm:
    """:math:`\\sum_i \\lVert X_i R_{cam} - f_i V_i \\rVert^2` (Eq. 6.9/10.1, second term);
    ``response`` is :math:`R_{cam}`, ``(K, channels)``, camera sensitivity times light."""

    response: np.ndarray
    target: np.ndarray  # (n_pixels, channels): f-scaled camera values

    @property
    def n_rows(self) -> int:
        return int(self.target.size)

    def apply(self, x: np.ndarray) -> np.ndarray:
        return x @ self.response

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        out += residual @ self.response.T


@dataclass(frozen=True)
class AppearancePriorTerm:
    """:math:`\\sum_i \\sum_{j \\in N_i} \\lVert X_i - X_j \\rVert^2` (Eq. 6.3) over the links of
    ``graph``: its difference operator :math:`D` (``incidence``, ``(links, n_pixels)``) and
    Laplacian :math:`D^T D` are built when first used."""

    graph: NeighbourGraph
    n_bands: int

    @cached_property
    def incidence(self) -> sparse.csr_matrix:
        return self.graph.incidence()

    @cached_property
    def laplacian(self) -> sparse.csr_matrix:
        return self.graph.laplacian()

    @property
    def n_rows(self) -> int:
        return self.graph.n_links * self.n_bands

    @property
    def target(self) -> np.ndarray:
        return np.zeros((self.graph.n_links, self.n_bands))

    def apply(self, x: np.ndarray) -> np.ndarray:
        return self.incidence @ x

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        out += self.incidence.T @ residual

    def sum_of_squares(self, x: np.ndarray) -> float:
        """:math:`\\lVert D X \\rVert_F^2 = \\mathrm{tr}(X^T D^T D X)`, without forming the
        ``(links, K)`` differences (three times the pixels)."""
        return float(np.einsum("ij,ij->", x, self.laplacian @ x))


@dataclass(frozen=True)
class SpectralSmoothnessTerm:
    """:math:`\\sum_i \\sum_{j<K} \\lVert X_{i,j} - X_{i,j+1} \\rVert^2` (Eq. 10.12, last term)."""

    n_pixels: int
    n_bands: int

    @property
    def n_rows(self) -> int:
        return self.n_pixels * (self.n_bands - 1)

    @property
    def target(self) -> np.ndarray:
        return np.zeros((self.n_pixels, self.n_bands - 1))

    def difference_matrix(self) -> np.ndarray:
        """``(K, K-1)`` matrix :math:`L_s` with :math:`X L_s` the band-to-band differences."""
        matrix = np.zeros((self.n_bands, self.n_bands - 1))
        columns = np.arange(self.n_bands - 1)
        matrix[columns, columns] = 1.0
        matrix[columns + 1, columns] = -1.0
        return matrix

    def apply(self, x: np.ndarray) -> np.ndarray:
        return x[:, :-1] - x[:, 1:]

    def adjoint(self, residual: np.ndarray, out: np.ndarray) -> None:
        out[:, :-1] += residual
        out[:, 1:] -= residual
