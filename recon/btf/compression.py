"""PCA compression of a spectral BTF: brightness and normalized spectra factorized separately.

Thesis 4.1.2, after Koudelka et al. [KMBK03] and Müller [Mül09]: "We first split the spectra of all
texels into a sum (brightness) and a normalized spectrum and factorize the two parts
individually ... 250 PCA components to represent [the brightness], whereas 60 components were
sufficient to reproduce each single band of the normalized spectra."

For a BTF :math:`R(p, t, \\lambda_k)` with P direction pairs, N = H W texels and K bands:

- brightness :math:`b(p, t) = \\sum_k R(p, t, \\lambda_k)`, a P x N matrix;
- normalized spectrum :math:`s(p, t, \\lambda_k) = R(p, t, \\lambda_k) / b(p, t)`; texels with
  :math:`|b| \\le` ``brightness_floor`` :math:`\\cdot \\max |b|` (shadowed, b = 0) get the flat
  spectrum 1/K, so they decode to b/K per band (0 where b = 0);
- each matrix :math:`M` (rows x N) is factorized by PCA over its rows:
  :math:`M \\approx \\mathbf{1} \\mu^T + A C` with the column mean :math:`\\mu` (N), scores
  :math:`A = U \\Sigma` (rows x c) and components :math:`C = V^T` (c x N) of the SVD of the
  centred matrix, truncated to c components.

Two layouts for the normalized spectra:

- ``"per_band"`` (the thesis): one PCA per band of the P x N matrix :math:`s(\\cdot, \\cdot,
  \\lambda_k)`, each with ``n_spectral`` components. Stored floats:
  :math:`K (N + c_s (P + N))`.
- ``"joint"``: one PCA of the (P K) x N matrix whose rows are all (pair, band) combinations,
  pair-major, with ``n_spectral`` components shared by all bands. Stored floats:
  :math:`N + c_s (P K + N)`: about K times fewer components, at the price of a basis that must
  serve every band at once.

The brightness costs :math:`N + c_b (P + N)` floats. Component counts are capped at the rank
limit of their matrix, min(rows, columns); the caps are reported (:attr:`CompressedBTF.caps`).
The compression ratio is raw float32 bytes :math:`4 P N K` over the float32 bytes of all stored
factors (means included): see :func:`predicted_ratio`. At the thesis's scale (6561 pairs,
800 x 800 texels, 33 bands) 250/60 components give 94.7x per band and 646.6x joint; the per-band
layout cannot reach 100x with 6561 pairs whatever the texture size (limit 95.6x).

The SVD is LAPACK's (``scipy.linalg.svd``, exact) or the randomized SVD of Halko et al.
(``sklearn.utils.extmath.randomized_svd``) when few components of a large matrix are kept.

References
----------
- The thesis, section 4.1.2 (BTF compression) and Eq. 6.8 (relative error).
- Koudelka, M. L., Magda, S., Belhumeur, P. N., & Kriegman, D. J. (2003). Acquisition,
  compression, and synthesis of bidirectional texture functions. 3rd International Workshop on
  Texture Analysis and Synthesis (Texture 2003), 59-64. [KMBK03]
- Müller, G. (2009). Data-driven methods for compression and editing of spatially varying
  appearance. PhD thesis, Universität Bonn. [Mül09]
- Halko, N., Martinsson, P. G., & Tropp, J. A. (2011). Finding structure with randomness:
  probabilistic algorithms for constructing approximate matrix decompositions. SIAM Review,
  53(2), 217-288. doi:10.1137/090771806
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import scipy.linalg
from sklearn.utils.extmath import randomized_svd

from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.metrics import relative_error
from recon.spectra import WavelengthGrid

__all__ = [
    "LAYOUTS",
    "CompressedBTF",
    "CompressionReport",
    "Layout",
    "SvdMethod",
    "compress_btf",
    "compressed_floats",
    "compression_report",
    "load_compressed",
    "predicted_ratio",
    "save_compressed",
]

Layout = Literal["per_band", "joint"]
SvdMethod = Literal["auto", "exact", "randomized"]
LAYOUTS = ("per_band", "joint")
_SVD_METHODS = ("auto", "exact", "randomized")
_FLOAT32_BYTES = 4
_ARRAY_NAMES = (
    "brightness/mean",
    "brightness/scores",
    "brightness/components",
    "spectral/mean",
    "spectral/scores",
    "spectral/components",
)


# -- sizes ----------------------------------------------------------------------------------------


def _caps(
    shape: tuple[int, int, int, int], n_brightness: int, n_spectral: int, layout: str
) -> tuple[int, int]:
    """Component counts after capping at min(rows, columns) of each factorized matrix."""
    n_pairs, height, width, n_bands = shape
    n_texels = height * width
    spectral_rows = n_pairs if layout == "per_band" else n_pairs * n_bands
    return min(n_brightness, n_pairs, n_texels), min(n_spectral, spectral_rows, n_texels)


def compressed_floats(
    shape: tuple[int, int, int, int],
    *,
    n_brightness: int = 250,
    n_spectral: int = 60,
    layout: Layout = "per_band",
) -> int:
    """Number of float32 values stored for a BTF of ``shape`` = (P, H, W, K) (caps applied).

    Brightness: ``N + c_b (P + N)``; per band: ``K (N + c_s (P + N))``; joint:
    ``N + c_s (P K + N)``, with N = H W (the means are the N and K N terms).
    """
    shape = _check_shape(shape)
    _check_options(n_brightness, n_spectral, layout, "auto")
    n_pairs, height, width, n_bands = shape
    n_texels = height * width
    c_b, c_s = _caps(shape, n_brightness, n_spectral, layout)
    brightness = n_texels + c_b * (n_pairs + n_texels)
    if layout == "per_band":
        spectral = n_bands * (n_texels + c_s * (n_pairs + n_texels))
    else:
        spectral = n_texels + c_s * (n_pairs * n_bands + n_texels)
    return int(brightness + spectral)


def predicted_ratio(
    shape: tuple[int, int, int, int],
    *,
    n_brightness: int = 250,
    n_spectral: int = 60,
    layout: Layout = "per_band",
) -> float:
    """Raw float32 size over compressed float32 size for a BTF of ``shape`` = (P, H, W, K).

    Examples
    --------
    >>> round(predicted_ratio((6561, 800, 800, 33)), 1)  # the thesis's BTF, per band
    94.7
    >>> round(predicted_ratio((6561, 800, 800, 33), layout="joint"))
    647
    """
    shape = _check_shape(shape)
    raw = int(np.prod(shape, dtype=np.int64))
    return raw / compressed_floats(
        shape, n_brightness=n_brightness, n_spectral=n_spectral, layout=layout
    )


# -- the compressed BTF ---------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class CompressedBTF:
    """A BTF as brightness and normalized-spectra PCA factors (float32).

    With N = H W texels, c_b brightness and c_s spectral components, and G = K groups for
    ``"per_band"`` or G = 1 for ``"joint"``:

    - ``brightness_mean`` (N,), ``brightness_scores`` (P, c_b), ``brightness_components``
      (c_b, N): :math:`b(p, \\cdot) = \\mu_b + A_b[p] C_b`;
    - ``spectral_mean`` (G, N), ``spectral_scores`` (P, K, c_s), ``spectral_components``
      (G, c_s, N): :math:`s(p, \\cdot, \\lambda_k) = \\mu_g + A_s[p, k] C_g` with g = k per band,
      g = 0 joint (the joint scores are the rows (p, k) of the (P K) x N factorization);
    - :math:`R = b \\, s`.
    """

    shape: tuple[int, int, int, int]
    grid: WavelengthGrid
    layout: Layout
    brightness_mean: np.ndarray
    brightness_scores: np.ndarray
    brightness_components: np.ndarray
    spectral_mean: np.ndarray
    spectral_scores: np.ndarray
    spectral_components: np.ndarray
    n_brightness_requested: int
    n_spectral_requested: int
    brightness_floor: float = 1e-6
    svd: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        shape = _check_shape(self.shape)
        object.__setattr__(self, "shape", shape)
        if not isinstance(self.grid, WavelengthGrid) or self.grid.size != shape[3]:
            raise InputError(
                f"grid: expected a WavelengthGrid of {shape[3]} bands, got {self.grid!r}"
            )
        if self.layout not in LAYOUTS:
            raise InputError(f"layout: expected one of {LAYOUTS}, got {self.layout!r}")
        n_pairs, height, width, n_bands = shape
        n_texels = height * width
        c_b = np.shape(self.brightness_scores)[-1] if np.ndim(self.brightness_scores) else -1
        c_s = np.shape(self.spectral_scores)[-1] if np.ndim(self.spectral_scores) else -1
        groups = n_bands if self.layout == "per_band" else 1
        expected = {
            "brightness_mean": (n_texels,),
            "brightness_scores": (n_pairs, c_b),
            "brightness_components": (c_b, n_texels),
            "spectral_mean": (groups, n_texels),
            "spectral_scores": (n_pairs, n_bands, c_s),
            "spectral_components": (groups, c_s, n_texels),
        }
        for name, want in expected.items():
            values = np.asarray(getattr(self, name))
            if values.shape != want:
                raise InputError(
                    f"{name}: expected shape {want} for a {self.layout} BTF of shape {shape}, "
                    f"got {values.shape}"
                )
            values = np.ascontiguousarray(values, dtype=np.float32)
            if not np.all(np.isfinite(values)):
                raise InputError(f"{name}: expected finite factors, found NaN")
            object.__setattr__(self, name, values)

    # -- sizes --

    @property
    def n_brightness(self) -> int:
        """Brightness components kept (after the cap)."""
        return self.brightness_scores.shape[1]

    @property
    def n_spectral(self) -> int:
        """Spectral components kept per factorization (after the cap)."""
        return self.spectral_scores.shape[2]

    @property
    def caps(self) -> dict[str, dict[str, int | bool]]:
        """Requested and kept component counts, and whether the rank limit capped them."""
        return {
            "brightness": {
                "requested": self.n_brightness_requested,
                "kept": self.n_brightness,
                "capped": self.n_brightness < self.n_brightness_requested,
            },
            "spectral": {
                "requested": self.n_spectral_requested,
                "kept": self.n_spectral,
                "capped": self.n_spectral < self.n_spectral_requested,
            },
        }

    @property
    def raw_nbytes(self) -> int:
        """Bytes of the uncompressed BTF as float32: 4 P H W K."""
        return _FLOAT32_BYTES * int(np.prod(self.shape, dtype=np.int64))

    @property
    def nbytes(self) -> int:
        """Bytes of all stored factors (means included) as float32."""
        return _FLOAT32_BYTES * sum(int(getattr(self, name).size) for name in _FIELDS)

    @property
    def compression_ratio(self) -> float:
        """``raw_nbytes / nbytes``."""
        return self.raw_nbytes / self.nbytes

    # -- decoding --

    def decode_pair(self, pair: int) -> np.ndarray:
        """The texture ``(H, W, K)`` float32 of one direction pair."""
        pair = self._check_index(pair, self.shape[0], "pair")
        _, height, width, n_bands = self.shape
        brightness = (
            self.brightness_mean + self.brightness_scores[pair] @ self.brightness_components
        )
        if self.layout == "joint":  # (K, c) @ (c, N)
            spectra = self.spectral_scores[pair] @ self.spectral_components[0]
        else:  # (K, 1, c) @ (K, c, N) -> (K, 1, N)
            spectra = (self.spectral_scores[pair][:, None, :] @ self.spectral_components)[:, 0]
        spectra += self.spectral_mean
        return (brightness[:, None] * spectra.T).reshape(height, width, n_bands)

    def decode_texel(self, y: int, x: int) -> np.ndarray:
        """The BRDF of texel ``(y, x)``: ``(n_pairs, K)`` float32, pairs in store order."""
        _, height, width, _ = self.shape
        texel = self._check_index(y, height, "y") * width + self._check_index(x, width, "x")
        brightness = (
            self.brightness_mean[texel]
            + self.brightness_scores @ self.brightness_components[:, texel]
        )
        columns = self.spectral_components[:, :, texel]  # (G, c), G = K or 1
        spectra = (
            np.einsum("pkc,kc->pk", self.spectral_scores, columns)
            if len(columns) > 1
            else self.spectral_scores @ columns[0]
        )
        spectra += self.spectral_mean[:, texel]
        return brightness[:, None] * spectra

    def decode(self) -> np.ndarray:
        """The whole BTF ``(n_pairs, H, W, K)`` float32."""
        n_pairs, height, width, n_bands = self.shape
        brightness = self.brightness_mean + self.brightness_scores @ self.brightness_components
        out = np.empty((n_pairs, height * width, n_bands), dtype=np.float32)
        for band in range(n_bands):
            group = band if self.layout == "per_band" else 0
            spectra = self.spectral_scores[:, band] @ self.spectral_components[group]
            spectra += self.spectral_mean[group]
            out[:, :, band] = brightness * spectra
        return out.reshape(self.shape)

    @staticmethod
    def _check_index(index: int, size: int, name: str) -> int:
        if isinstance(index, bool) or not isinstance(index, int | np.integer):
            raise InputError(f"{name}: expected an integer index, got {index!r}")
        if not 0 <= index < size:
            raise InputError(f"{name}: expected an index in 0..{size - 1}, got {index}")
        return int(index)

    def __repr__(self) -> str:
        return (
            f"CompressedBTF(shape={self.shape}, layout={self.layout!r}, "
            f"brightness={self.n_brightness}/{self.n_brightness_requested}, "
            f"spectral={self.n_spectral}/{self.n_spectral_requested}, "
            f"ratio={self.compression_ratio:.1f})"
        )


_FIELDS = tuple(name.replace("/", "_") for name in _ARRAY_NAMES)


# -- compression ---------------------------------------------------------------------------------


def _check_shape(shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    shape = tuple(shape)
    if len(shape) != 4 or not all(
        isinstance(n, int | np.integer) and not isinstance(n, bool) and n > 0 for n in shape
    ):
        raise InputError(f"shape: expected (n_pairs, H, W, K) of positive ints, got {shape!r}")
    n_pairs, height, width, bands = (int(n) for n in shape)
    return n_pairs, height, width, bands


def _check_options(n_brightness: int, n_spectral: int, layout: str, svd: str) -> None:
    for name, value in (("n_brightness", n_brightness), ("n_spectral", n_spectral)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise InputError(f"{name}: expected a positive integer, got {value!r}")
    if layout not in LAYOUTS:
        raise InputError(f"layout: expected one of {LAYOUTS}, got {layout!r}")
    if svd not in _SVD_METHODS:
        raise InputError(f"svd: expected one of {_SVD_METHODS}, got {svd!r}")


def _pca(
    matrix: np.ndarray, n_components: int, *, svd: str, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Column mean (cols,), scores U S (rows, c) and components V^T (c, cols), float32.

    ``matrix`` may be overwritten (it is centred in place).
    """
    rows, cols = matrix.shape
    mean = matrix.mean(axis=0, dtype=np.float64)
    exact = svd == "exact" or (svd == "auto" and n_components >= 0.25 * min(rows, cols))
    if exact:
        centred = matrix.astype(np.float64) - mean
        try:
            u, sigma, vt = scipy.linalg.svd(centred, full_matrices=False, lapack_driver="gesdd")
        except np.linalg.LinAlgError:
            u, sigma, vt = scipy.linalg.svd(centred, full_matrices=False, lapack_driver="gesvd")
        method = "exact"
    else:
        matrix -= mean.astype(matrix.dtype)
        u, sigma, vt = randomized_svd(matrix, n_components, random_state=seed)
        method = "randomized"
    scores = (u[:, :n_components] * sigma[:n_components]).astype(np.float32)
    return mean.astype(np.float32), scores, vt[:n_components].astype(np.float32), method


def compress_btf(
    reflectance: np.ndarray,
    grid: WavelengthGrid,
    *,
    n_brightness: int = 250,
    n_spectral: int = 60,
    layout: Layout = "per_band",
    svd: SvdMethod = "auto",
    brightness_floor: float = 1e-6,
    rng: np.random.Generator | None = None,
) -> CompressedBTF:
    """Compress a spectral BTF by PCA of its brightness and normalized spectra (thesis 4.1.2).

    Parameters
    ----------
    reflectance
        ``(n_pairs, H, W, K)`` finite reflectance (1/sr), band axis last.
    grid
        The grid of the band axis.
    n_brightness
        PCA components of the (pairs x texels) brightness matrix (thesis: 250).
    n_spectral
        PCA components of each band's (pairs x texels) normalized-spectrum matrix (thesis: 60),
        or of the single (pairs x bands) x texels matrix with ``layout="joint"``.
    layout
        ``"per_band"`` (the thesis) or ``"joint"`` (see the module docstring).
    svd
        ``"exact"`` (LAPACK), ``"randomized"`` (Halko et al.), or ``"auto"``: exact when the
        kept components are at least a quarter of the matrix's smaller side.
    brightness_floor
        Texels with ``|b| <= brightness_floor * max|b|`` get the flat normalized spectrum 1/K.
    rng
        Source of the randomized SVD's seed (default ``numpy.random.default_rng(0)``); the seed
        drawn is recorded in :attr:`CompressedBTF.svd`.

    Returns
    -------
    CompressedBTF
        Component counts capped at min(rows, columns) of each matrix (see ``caps``).

    Examples
    --------
    >>> compressed = compress_btf(store.read(), store.grid)  # doctest: +SKIP
    >>> compressed.compression_ratio  # doctest: +SKIP
    """
    _check_options(n_brightness, n_spectral, layout, svd)
    if not isinstance(grid, WavelengthGrid):
        raise InputError(f"grid: expected a WavelengthGrid, got {type(grid).__name__}")
    values = np.asarray(reflectance)
    if values.ndim != 4:
        raise InputError(f"reflectance: expected (n_pairs, H, W, K), got shape {values.shape}")
    if values.shape[3] != grid.size:
        raise InputError(
            f"reflectance: its last axis has {values.shape[3]} bands, the grid {grid.describe()}"
        )
    if not np.issubdtype(values.dtype, np.number) or np.issubdtype(
        values.dtype, np.complexfloating
    ):
        raise InputError(f"reflectance: expected real numbers, got {values.dtype}")
    values = values.astype(np.float32, copy=False)
    if not np.all(np.isfinite(values)):
        raise InputError("reflectance: expected finite values, found NaN or infinity")
    if not 0 <= brightness_floor < 1:
        raise InputError(f"brightness_floor: expected a fraction in [0, 1), got {brightness_floor}")
    shape = _check_shape(values.shape)
    n_pairs, height, width, n_bands = shape
    n_texels = height * width
    c_b, c_s = _caps(shape, n_brightness, n_spectral, layout)
    rng = np.random.default_rng(0) if rng is None else rng
    seed = int(rng.integers(2**31 - 1))

    flat = values.reshape(n_pairs, n_texels, n_bands)
    brightness = flat.sum(axis=-1, dtype=np.float64)
    dark = np.abs(brightness) <= brightness_floor * np.abs(brightness).max()
    safe = np.where(dark, 1.0, brightness)
    b_mean, b_scores, b_components, b_method = _pca(
        brightness.astype(np.float32), c_b, svd=svd, seed=seed
    )

    methods = []
    if layout == "per_band":
        s_mean = np.empty((n_bands, n_texels), np.float32)
        s_scores = np.empty((n_pairs, n_bands, c_s), np.float32)
        s_components = np.empty((n_bands, c_s, n_texels), np.float32)
        for band in range(n_bands):
            spectra = (flat[:, :, band] / safe).astype(np.float32)
            spectra[dark] = 1.0 / n_bands
            s_mean[band], s_scores[:, band], s_components[band], method = _pca(
                spectra, c_s, svd=svd, seed=seed + 1 + band
            )
            methods.append(method)
    else:
        # Rows (pair, band), pair-major; a (P K) x N matrix built one pair at a time.
        spectra = np.empty((n_pairs, n_bands, n_texels), np.float32)
        for pair in range(n_pairs):
            spectra[pair] = (flat[pair] / safe[pair][:, None]).T
            spectra[pair][:, dark[pair]] = 1.0 / n_bands
        mean, scores, components, method = _pca(
            spectra.reshape(n_pairs * n_bands, n_texels), c_s, svd=svd, seed=seed + 1
        )
        del spectra
        s_mean, s_components = mean[None], components[None]
        s_scores = scores.reshape(n_pairs, n_bands, c_s)
        methods.append(method)

    return CompressedBTF(
        shape=shape,
        grid=grid,
        layout=layout,
        brightness_mean=b_mean,
        brightness_scores=b_scores,
        brightness_components=b_components,
        spectral_mean=s_mean,
        spectral_scores=s_scores,
        spectral_components=s_components,
        n_brightness_requested=int(n_brightness),
        n_spectral_requested=int(n_spectral),
        brightness_floor=float(brightness_floor),
        svd={
            "requested": svd,
            "brightness": b_method,
            "spectral": sorted(set(methods)),
            "seed": seed,
            "dark_texels": int(dark.sum()),
        },
    )


# -- evaluation -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class CompressionReport:
    """Size and error of a compressed BTF against its reference.

    Errors: ``mean_relative_error_percent`` is Eq. 6.8 (``recon.metrics.relative_error``,
    per texel spectrum) averaged over all pairs and texels, ``max_relative_error_percent`` its
    maximum; ``rmse`` and ``max_abs_error`` are over all values, in 1/sr.
    """

    raw_bytes: int
    compressed_bytes: int
    ratio: float
    mean_relative_error_percent: float
    max_relative_error_percent: float
    rmse: float
    max_abs_error: float
    layout: str
    n_brightness: int
    n_spectral: int
    n_brightness_requested: int
    n_spectral_requested: int

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def compression_report(
    compressed: CompressedBTF, reference: np.ndarray | BTFStore, *, eps: float = 1e-3
) -> CompressionReport:
    """Sizes and errors of ``compressed`` against ``reference`` (an array or a complete store),
    evaluated one direction pair at a time.

    ``eps`` is the constant of Eq. 6.8 that down-weights dark values.
    """
    if isinstance(reference, BTFStore):
        if reference.grid != compressed.grid:
            raise InputError(
                f"reference: store grid {reference.grid.describe()} differs from the compressed "
                f"BTF's {compressed.grid.describe()}"
            )
        store = reference
        store_shape = store.shape
        store.reflectance()  # raises when the store is incomplete

        def pair_values(pair: int) -> np.ndarray:
            return store.read_pair(pair)
    else:
        values = np.asarray(reference)
        store_shape = values.shape

        def pair_values(pair: int) -> np.ndarray:
            return np.asarray(values[pair])

    if tuple(store_shape) != compressed.shape:
        raise InputError(
            f"reference: shape {tuple(store_shape)} differs from the compressed BTF's "
            f"{compressed.shape}"
        )
    total_relative, max_relative, squares, max_abs = 0.0, 0.0, 0.0, 0.0
    for pair in range(compressed.shape[0]):
        truth = np.asarray(pair_values(pair), dtype=np.float64)
        estimate = compressed.decode_pair(pair).astype(np.float64)
        relative = relative_error(estimate, truth, eps=eps)
        total_relative += float(relative.sum())
        max_relative = max(max_relative, float(relative.max()))
        difference = estimate - truth
        squares += float(np.sum(difference**2))
        max_abs = max(max_abs, float(np.abs(difference).max()))
    n_pairs, height, width, n_bands = compressed.shape
    return CompressionReport(
        raw_bytes=compressed.raw_nbytes,
        compressed_bytes=compressed.nbytes,
        ratio=compressed.compression_ratio,
        mean_relative_error_percent=total_relative / (n_pairs * height * width),
        max_relative_error_percent=max_relative,
        rmse=float(np.sqrt(squares / (n_pairs * height * width * n_bands))),
        max_abs_error=max_abs,
        layout=compressed.layout,
        n_brightness=compressed.n_brightness,
        n_spectral=compressed.n_spectral,
        n_brightness_requested=compressed.n_brightness_requested,
        n_spectral_requested=compressed.n_spectral_requested,
    )


# -- storage ----------------------------------------------------------------------------------


def _as_store(store: BTFStore | str | Path, *, writable: bool) -> BTFStore:
    if isinstance(store, BTFStore):
        return store
    return BTFStore.open(store, writable=writable)


def save_compressed(store: BTFStore | str | Path, compressed: CompressedBTF) -> None:
    """Write ``compressed`` into the ``pca/`` group of a complete BTF store of the same shape and
    grid (replacing an earlier compressed form; marked complete only once fully written)."""
    store = _as_store(store, writable=True)
    if store.shape != compressed.shape or store.grid != compressed.grid:
        raise InputError(
            f"compressed: shape {compressed.shape} on {compressed.grid.describe()} does not "
            f"match the store's {store.shape} on {store.grid.describe()}"
        )
    arrays = {name: getattr(compressed, name.replace("/", "_")) for name in _ARRAY_NAMES}
    store.write_compressed(
        arrays,
        {
            "method": "brightness and normalized spectra PCA (thesis 4.1.2)",
            "layout": compressed.layout,
            "shape": list(compressed.shape),
            "n_brightness_requested": compressed.n_brightness_requested,
            "n_spectral_requested": compressed.n_spectral_requested,
            "brightness_floor": compressed.brightness_floor,
            "svd": compressed.svd,
            "compression_ratio": compressed.compression_ratio,
        },
    )


def load_compressed(store: BTFStore | str | Path) -> CompressedBTF:
    """The compressed BTF stored in ``store``'s ``pca/`` group."""
    store = _as_store(store, writable=False)
    arrays, attrs = store.read_compressed()
    missing = [name for name in _ARRAY_NAMES if name not in arrays]
    if missing:
        raise InputError(f"{store.path}: the compressed form lacks arrays {missing}")
    return CompressedBTF(
        shape=attrs.shape,
        grid=store.grid,
        layout=attrs.layout,
        **{name.replace("/", "_"): arrays[name] for name in _ARRAY_NAMES},
        n_brightness_requested=attrs.n_brightness_requested,
        n_spectral_requested=attrs.n_spectral_requested,
        brightness_floor=attrs.brightness_floor,
        svd=dict(attrs.svd),
    )
