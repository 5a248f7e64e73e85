"""A measured spectral BTF as a Mitsuba BSDF (Python plugin ``spectral_btf``), thesis 4.2.

A BTF measured on a light x view product set of directions (Sattler's 81 x 81, or the twin's
reduced 13 x 13) is rendered by interpolating, per shading point:

- in direction: barycentric interpolation on the hemisphere, separately for the light and the
  view direction (Delaunay triangulation of the directions' orthographic projections onto the
  unit disk, precomputed on a ``resolution x resolution`` lookup grid; outside the measured
  directions' hull the nearest direction is used), i.e. 3 x 3 measured pairs per lookup;
- in space: bilinear between texels (texture coordinates ``uv`` of the shape, texel ``(i, j)``
  at ``u = (j + 0.5) / W``, ``v = 1 - (i + 0.5) / H``: rows run from the sample's +y edge down,
  as in the BTF store);
- in wavelength: linear between bands, constant beyond the first and last band.

Pairs the rig could not measure (light and view too close) are filled from the nearest measured
view of the same light. Directions use the shading frame (x = dp/du), as the BTF uses the
sample frame. The BSDF samples the cosine-weighted hemisphere. A BTF sampled from a known BRDF
renders like the BRDF itself (``tests/twin/test_btf_bsdf.py``).

The BTF is either decoded (:class:`BTFTable`, ``4 L V H W K`` bytes) or PCA-compressed
(:class:`CompressedTable`, :mod:`recon.btf.compression`, thesis 4.1.2). A compressed BTF stays
compressed on the renderer's side: :math:`R = b \\, s` with the brightness
:math:`b = \\mu_b + A_b[p] C_b` decoded per pair and texel (a K-th of the decoded table) and the
spectral factor :math:`s = \\mu_s + A_s[p, k] C_s` decoded per lookup, all of a lookup's 9
direction pairs x 4 texels in one Dr.Jit loop of ``c_s`` steps (:class:`_CompressedSpectra`).

Importing this module activates the Mitsuba variant (:func:`twin.render.variant.activate`):
:class:`SpectralBTF` derives from the variant's ``mi.BSDF`` and is registered with Mitsuba at
import (:mod:`twin.render.plugins.registry`).
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np
from scipy.spatial import Delaunay

from recon.btf.compression import CompressedBTF, load_compressed
from recon.btf.specular_lobe import COATING_IOR, SpecularLobes, fit_specular_lobes
from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.render.plugins.registry import PluginData, register_once
from twin.render.variant import activate

__all__ = [
    "BTFTable",
    "CompressedTable",
    "SpectralBTF",
    "compressed_product_table",
    "store_table",
    "barycentric",
    "btf_bsdf",
    "hemisphere_lookup",
    "interpolate_table",
    "product_table",
    "written_table",
]

# mi.BSDF below is the active variant's class: choose the variant before defining the plugin.
activate()

_TABLES = PluginData("btf")


@dataclass(frozen=True)
class BTFTable:
    """A BTF on a product set: ``values`` ``(n_lights, n_views, H, W, K)`` in 1/sr; with
    ``lobes`` (:mod:`recon.btf.specular_lobe`) the values are the residual and the BTF is their
    interpolation plus the lobes, evaluated at the looked-up directions."""

    light_dirs: np.ndarray
    view_dirs: np.ndarray
    values: np.ndarray
    grid: WavelengthGrid
    lobes: SpecularLobes | None = None

    def __post_init__(self) -> None:
        shape = self.values.shape
        if (
            len(shape) != 5
            or shape[:2] != (len(self.light_dirs), len(self.view_dirs))
            or shape[4] != self.grid.size
        ):
            raise InputError(
                f"values: expected (n_lights, n_views, H, W, K) = ({len(self.light_dirs)}, "
                f"{len(self.view_dirs)}, H, W, {self.grid.size}), got {shape}"
            )
        if not np.all(np.isfinite(self.values)):
            raise InputError("values: expected finite reflectance")
        _check_regular(self.grid)

    @property
    def nbytes(self) -> int:
        """Bytes the renderer holds for the reflectance (float32)."""
        return 4 * self.values.size

    def texture(self, light: int, view: int) -> np.ndarray:
        """The texture ``(H, W, K)`` of the product set's ``(light, view)`` combination (with
        lobes: the residual, :func:`interpolate_table` adds them)."""
        return self.values[light, view]


@dataclass(frozen=True)
class CompressedTable:
    """A PCA-compressed BTF on a product set: combination ``(light, view)`` reads the
    compressed BTF's pair ``pairs[light, view]``."""

    light_dirs: np.ndarray
    view_dirs: np.ndarray
    pairs: np.ndarray
    compressed: CompressedBTF
    lobes: None = None  # a compressed BTF is rendered without fitted lobes

    def __post_init__(self) -> None:
        want = (len(self.light_dirs), len(self.view_dirs))
        if self.pairs.shape != want:
            raise InputError(f"pairs: expected shape {want}, got {self.pairs.shape}")
        n_pairs = self.compressed.shape[0]
        if self.pairs.min() < 0 or self.pairs.max() >= n_pairs:
            raise InputError(f"pairs: expected indices of the compressed BTF's {n_pairs} pairs")
        _check_regular(self.compressed.grid)

    @property
    def grid(self) -> WavelengthGrid:
        return self.compressed.grid

    @property
    def nbytes(self) -> int:
        """Bytes the renderer holds for the reflectance (float32): the spectral factors and the
        brightness decoded per pair and texel (:class:`_CompressedSpectra`)."""
        compressed = self.compressed
        n_pairs, height, width, _ = compressed.shape
        spectral = (
            compressed.spectral_mean.size
            + compressed.spectral_scores.size
            + compressed.spectral_components.size
        )
        return 4 * (spectral + n_pairs * height * width)

    def texture(self, light: int, view: int) -> np.ndarray:
        """The decoded texture ``(H, W, K)`` of the combination ``(light, view)``."""
        return self.compressed.decode_pair(int(self.pairs[light, view]))


def _check_regular(grid: WavelengthGrid) -> None:
    steps = np.diff(grid.wavelengths_nm)
    if steps.size and not np.allclose(steps, steps[0]):
        raise InputError("grid: expected a regular wavelength grid (resample first)")


def _unique_directions(directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rounded = np.round(np.asarray(directions, np.float64), 9)
    unique, inverse = np.unique(rounded, axis=0, return_inverse=True)
    return unique / np.linalg.norm(unique, axis=1, keepdims=True), inverse.ravel()


def _product_set(
    light_dirs: np.ndarray, view_dirs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct lights and views of pairs given by their directions, and for every light x
    view combination the pair it reads: its own, or the nearest measured view of its light."""
    lights, light_index = _unique_directions(light_dirs)
    views, view_index = _unique_directions(view_dirs)
    pairs = np.full((len(lights), len(views)), -1, np.int64)
    pairs[light_index, view_index] = np.arange(len(light_index))
    for light in range(len(lights)):
        have = np.flatnonzero(pairs[light] >= 0)
        if have.size == 0:
            raise InputError(f"light direction {lights[light].tolist()} has no views")
        for view in np.flatnonzero(pairs[light] < 0):
            pairs[light, view] = pairs[light, have[np.argmax(views[have] @ views[view])]]
    return lights, views, pairs


def product_table(
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    reflectance: np.ndarray,
    grid: WavelengthGrid,
    *,
    lobes: bool = False,
) -> BTFTable:
    """Arrange pairs ``(n_pairs, H, W, K)`` (e.g. a BTF store's) on their light x view product
    set; a missing combination takes the nearest measured view of the same light. With
    ``lobes`` a specular lobe is fitted per texel
    (:func:`recon.btf.specular_lobe.fit_specular_lobes`) and the table holds the residual."""
    values = np.asarray(reflectance, np.float32)
    fitted = None
    if lobes:
        fitted = fit_specular_lobes(light_dirs, view_dirs, values)
        values = fitted.residual(np.asarray(light_dirs), np.asarray(view_dirs), values)
    lights, views, pairs = _product_set(light_dirs, view_dirs)
    return BTFTable(lights, views, values[pairs], grid, fitted)


def compressed_product_table(
    light_dirs: np.ndarray, view_dirs: np.ndarray, compressed: CompressedBTF
) -> CompressedTable:
    """The compressed BTF's pairs (directions in its pair order) on their product set, filled
    like :func:`product_table`."""
    if len(light_dirs) != compressed.shape[0] or len(view_dirs) != compressed.shape[0]:
        raise InputError(
            f"light_dirs, view_dirs: expected one per compressed pair ({compressed.shape[0]}), "
            f"got {len(light_dirs)} and {len(view_dirs)}"
        )
    lights, views, pairs = _product_set(light_dirs, view_dirs)
    return CompressedTable(lights, views, pairs, compressed)


def written_table(btf: BTFStore, *, lobes: bool = False) -> BTFTable:
    """The written pairs of a BTF store on their product set (:func:`product_table`)."""
    written = np.flatnonzero(btf.written())
    values = np.stack([btf.read_pair(int(pair), allow_incomplete=True) for pair in written])
    return product_table(
        btf.light_dirs[written], btf.view_dirs[written], values, btf.grid, lobes=lobes
    )


def store_table(
    btf: BTFStore, *, compressed: bool = False, lobes: bool = False
) -> BTFTable | CompressedTable:
    """A BTF store as the plugin's table: its written pairs decoded (:func:`written_table`,
    with ``lobes`` fitted), or with ``compressed`` its ``pca/`` form (``spectwin compress``),
    left compressed."""
    if not compressed:
        return written_table(btf, lobes=lobes)
    return compressed_product_table(btf.light_dirs, btf.view_dirs, load_compressed(btf))


def barycentric(directions: np.ndarray, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices and weights ``(n, 3)`` interpolating ``directions`` at ``queries`` ``(n, 3)`` (or
    their ``(n, 2)`` disk projections): barycentric in the Delaunay triangulation of the
    directions' orthographic projections, the nearest direction outside their hull (and
    everywhere when the projections lie on one line: no triangle to interpolate in)."""
    points = np.asarray(directions, np.float64)[:, :2]
    queries = np.asarray(queries, np.float64)[:, :2]
    indices = np.zeros((queries.shape[0], 3), np.int64)
    weights = np.zeros((queries.shape[0], 3))
    inside = np.zeros(queries.shape[0], bool)
    if np.linalg.matrix_rank(points - points.mean(axis=0), tol=1e-9) == 2:
        triangulation = Delaunay(points)
        simplex = triangulation.find_simplex(queries)
        inside = simplex >= 0
        transform = triangulation.transform[simplex[inside]]
        partial = np.einsum("nij,nj->ni", transform[:, :2], queries[inside] - transform[:, 2])
        weights[inside] = np.column_stack([partial, 1 - partial.sum(axis=1)])
        indices[inside] = triangulation.simplices[simplex[inside]]
    nearest = np.argmin(((queries[~inside, None] - points[None]) ** 2).sum(axis=2), axis=1)
    indices[~inside] = nearest[:, None]
    weights[~inside] = [1.0, 0.0, 0.0]
    return indices, np.clip(weights, 0, 1)


def hemisphere_lookup(directions: np.ndarray, resolution: int = 128):
    """Barycentric weights over ``directions`` (:func:`barycentric`) on a grid over the unit disk.

    Returns ``(indices, weights)``, each ``(resolution, resolution, 3)``: grid cell ``(a, b)``
    holds the point ``x = -1 + (b + 0.5) 2 / resolution``, ``y = -1 + (a + 0.5) 2 / resolution``
    of the orthographic projection (a direction's ``(x, y)``).
    """
    centres = -1 + (np.arange(resolution) + 0.5) * 2 / resolution
    x, y = np.meshgrid(centres, centres)
    indices, weights = barycentric(directions, np.column_stack([x.ravel(), y.ravel()]))
    shape = (resolution, resolution, 3)
    return indices.reshape(shape), weights.reshape(shape)


def interpolate_table(
    table: BTFTable | CompressedTable, light: np.ndarray, view: np.ndarray
) -> np.ndarray:
    """The table's texture ``(H, W, K)`` at one (light, view) pair, interpolated like the plugin
    does (without its lookup grid)."""
    light_indices, light_weights = barycentric(table.light_dirs, np.atleast_2d(light))
    view_indices, view_weights = barycentric(table.view_dirs, np.atleast_2d(view))
    texture: np.ndarray | float = 0.0
    for i, wi in zip(light_indices[0], light_weights[0], strict=True):
        for j, wj in zip(view_indices[0], view_weights[0], strict=True):
            if wi * wj > 0:
                texture = texture + wi * wj * table.texture(i, j).astype(np.float64)
    if table.lobes is not None:
        lobes = table.lobes.values(np.atleast_2d(light), np.atleast_2d(view))
        texture = texture + lobes[0][..., None]
    return np.asarray(texture)


def btf_bsdf(table: BTFTable | CompressedTable, *, resolution: int = 128) -> dict[str, object]:
    """Scene-dict entry of the BSDF for ``table``.

    Parameters
    ----------
    table : BTFTable or CompressedTable
        The BTF on its light x view product set.
    resolution : int, optional
        Cells per side of the hemisphere lookup grids (:func:`hemisphere_lookup`).

    Returns
    -------
    dict
        The ``spectral_btf`` entry for ``mi.load_dict``; the table is kept for the plugin by key.
    """
    return {"type": "spectral_btf", "btf": _TABLES.keep(table), "resolution": resolution}


class _KernelSizes:
    """A BTF table's sizes as opaque Dr.Jit values: they enter the kernels as variables, not
    literals, so a table of other sizes reuses the compiled kernels (the same values)."""

    def __init__(self, views: int, rows: int, columns: int, bands: int):
        self.shape = (views, rows, columns, bands)  # the plain numbers, for printing

        def opaque(value: int):
            return dr.opaque(mi.UInt32, value)

        self.views, self.rows, self.columns = opaque(views), opaque(rows), opaque(columns)
        self.texels, self.bands = opaque(rows * columns), opaque(bands)
        # the last first index of a pair of neighbours (0 for a single row, column or band)
        self.last_row_pair = opaque(max(rows - 2, 0))
        self.last_column_pair = opaque(max(columns - 2, 0))
        self.last_band_pair = opaque(max(bands - 2, 0))


class _DecodedSpectra:
    """Texel spectra of a :class:`BTFTable`, gathered from its values (Dr.Jit side)."""

    def __init__(self, table: BTFTable):
        self.sizes = _KernelSizes(*table.values.shape[1:])
        self._values = mi.Float(table.values.astype(np.float32).ravel())

    def blend(self, combinations, texels, lows, fractions, active):
        """Reflectance per wavelength channel, the weighted sum over the product set's
        ``combinations`` (``(light * n_views + view, weight)``) and ``texels`` (``(offset,
        weight)``) of their spectra, linear between the bands ``lows`` and ``lows + 1``."""
        channels = [mi.Float(0.0) for _ in lows]
        for combination, combination_weight in combinations:
            for texel, texel_weight in texels:
                weight = combination_weight * texel_weight
                mask = active & (weight > 0)
                base = (combination * self.sizes.texels + texel) * self.sizes.bands
                for channel, (low, fraction) in enumerate(zip(lows, fractions, strict=True)):
                    first = dr.gather(mi.Float, self._values, base + low, mask)
                    high = dr.minimum(low + 1, self.sizes.bands - 1)
                    second = dr.gather(mi.Float, self._values, base + high, mask)
                    value = first + fraction * (second - first)
                    channels[channel] += dr.select(mask, weight * value, 0.0)
        return channels


class _CompressedSpectra:
    """Texel spectra of a :class:`CompressedTable`, decoded from the PCA factors per lookup.

    The brightness :math:`b = \\mu_b + A_b C_b` is decoded once per pair and texel when the BSDF
    is built (``n_pairs H W`` values, a K-th of the decoded table). The spectral factor is linear
    in its components, so a lookup's blend over the direction pairs :math:`p` and texels
    :math:`t` is one sum over the components,
    :math:`\\sum_c \\sum_p w_p A_s[p, \\lambda, c] \\sum_t w_t b[p, t] C_s[c, t]` plus the
    mean's term: a single Dr.Jit loop of ``c_s`` steps per lookup, its state four channels.
    """

    def __init__(self, table: CompressedTable):
        compressed = table.compressed
        self.sizes = _KernelSizes(len(table.view_dirs), *compressed.shape[1:])
        self._per_band = compressed.layout == "per_band"
        self._n_spectral = dr.opaque(mi.UInt32, compressed.n_spectral)
        self._pairs = mi.UInt32(table.pairs.ravel().astype(np.uint32))
        brightness = compressed.brightness_mean + (
            compressed.brightness_scores @ compressed.brightness_components
        )
        self._brightness = mi.Float(np.asarray(brightness, np.float32).ravel())
        self._factors = {
            name: mi.Float(np.asarray(getattr(compressed, name), np.float32).ravel())
            for name in ("spectral_mean", "spectral_scores", "spectral_components")
        }

    def _gather(self, name, index, mask):
        return dr.gather(mi.Float, self._factors[name], index, mask)

    def blend(self, combinations, texels, lows, fractions, active):
        """As :meth:`_DecodedSpectra.blend`, decoding from the factors (class docstring)."""
        n_texels, c_s, bands = self.sizes.texels, self._n_spectral, self.sizes.bands
        pairs = [
            (dr.gather(mi.UInt32, self._pairs, combination, active), weight)
            for combination, weight in combinations
        ]
        # beta[p][t] = w_p w_t b[p, t]: the brightness-weighted blend of pair p's texels
        beta = [
            [
                pair_weight
                * texel_weight
                * dr.gather(mi.Float, self._brightness, pair * n_texels + texel, active)
                for texel, texel_weight in texels
            ]
            for pair, pair_weight in pairs
        ]
        highs = [dr.minimum(low + 1, bands - 1) for low in lows]
        ends = [(low, high) for low, high in zip(lows, highs, strict=True)]

        def blended(name, group_offset):
            """sum_t beta[p][t] X[g, t] per pair p, for the factor ``name`` of one group g."""
            values = [self._gather(name, group_offset + texel, active) for texel, _ in texels]
            return [sum(b * v for b, v in zip(row, values, strict=True)) for row in beta]

        def per_channel(name, offset_of):
            """:func:`blended` at both ends (low, high band) of every channel: the bands' own
            groups in the per-band layout, the one group of the joint layout otherwise."""
            if not self._per_band:
                shared = blended(name, offset_of(mi.UInt32(0)))
                return [(shared, shared)] * len(ends)
            return [
                (blended(name, offset_of(low)), blended(name, offset_of(high)))
                for low, high in ends
            ]

        means = per_channel("spectral_mean", lambda group: group * n_texels)
        channels = [
            sum(
                (1 - fraction) * low_mean + fraction * high_mean
                for low_mean, high_mean in zip(*mean, strict=True)
            )
            for mean, fraction in zip(means, fractions, strict=True)
        ]

        def body(component, *sums):
            gammas = per_channel(
                "spectral_components", lambda group: (group * c_s + component) * n_texels
            )
            updated = []
            for total, (low, high), fraction, (gamma_low, gamma_high) in zip(
                sums, ends, fractions, gammas, strict=True
            ):
                for (pair, _), g_low, g_high in zip(pairs, gamma_low, gamma_high, strict=True):
                    row = pair * bands
                    score_low = self._gather(
                        "spectral_scores", (row + low) * c_s + component, active
                    )
                    score_high = self._gather(
                        "spectral_scores", (row + high) * c_s + component, active
                    )
                    total = (
                        total + (1 - fraction) * score_low * g_low + fraction * score_high * g_high
                    )
                updated.append(total)
            return (component + 1, *updated)

        width = dr.width(active)
        state = (dr.zeros(mi.UInt32, width), *[dr.zeros(mi.Float, width) for _ in lows])
        sums = dr.while_loop(state, lambda component, *_: component < c_s, body)[1:]
        return [
            dr.select(active, mean + total, 0.0) for mean, total in zip(channels, sums, strict=True)
        ]


class SpectralBTF(mi.BSDF):
    """The ``spectral_btf`` BSDF: a BTF table interpolated per shading point (module docstring).

    Parameters
    ----------
    props : mitsuba.Properties
        ``btf``: the key of the table (:func:`btf_bsdf`); ``resolution``: cells per side of the
        hemisphere lookup grids (default 128).
    """

    def __init__(self, props):
        super().__init__(props)
        table = _TABLES[props["btf"]]
        self._resolution = int(props.get("resolution", 128))
        if isinstance(table, CompressedTable):
            self._spectra = _CompressedSpectra(table)
        else:
            self._spectra = _DecodedSpectra(table)
        self._lookups = []
        for directions in (table.light_dirs, table.view_dirs):
            indices, weights = hemisphere_lookup(directions, self._resolution)
            self._lookups.append(
                (mi.UInt32(indices.ravel().astype(np.uint32)), mi.Float(weights.ravel()))
            )
        self._lobes = None
        lobes = table.lobes
        if lobes is not None and lobes.weight.any():
            self._lobes = tuple(
                mi.Float(np.asarray(values, np.float32).ravel())
                for values in (lobes.roughness, lobes.weight, lobes.beckmann)
            )
        wavelengths = table.grid.wavelengths_nm
        self._first_nm = float(wavelengths[0])
        self._step_nm = float(wavelengths[1] - wavelengths[0]) if len(wavelengths) > 1 else 1.0
        flags = (
            mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.SpatiallyVarying
        )
        self.m_components = [flags]
        self.m_flags = flags

    def _corners(self, which, direction):
        """Three (direction index, weight) of the lookup grid cell of ``direction``."""
        indices, weights = self._lookups[which]
        scale = self._resolution / 2
        column = dr.clip(mi.Int32(dr.floor((direction.x + 1) * scale)), 0, self._resolution - 1)
        row = dr.clip(mi.Int32(dr.floor((direction.y + 1) * scale)), 0, self._resolution - 1)
        cell = mi.UInt32(row * self._resolution + column) * 3
        return [
            (dr.gather(mi.UInt32, indices, cell + k), dr.gather(mi.Float, weights, cell + k))
            for k in range(3)
        ]

    def _texels(self, uv):
        """Four (texel offset, weight) of the bilinear footprint of ``uv``."""
        sizes = self._spectra.sizes
        height, width = sizes.rows, sizes.columns
        x = dr.clip(uv.x * mi.Float(width) - 0.5, 0.0, mi.Float(width - 1))
        y = dr.clip((1 - uv.y) * mi.Float(height) - 0.5, 0.0, mi.Float(height - 1))
        x0 = dr.minimum(mi.UInt32(x), sizes.last_column_pair)
        y0 = dr.minimum(mi.UInt32(y), sizes.last_row_pair)
        fx, fy = dr.clip(x - mi.Float(x0), 0, 1), dr.clip(y - mi.Float(y0), 0, 1)
        x1, y1 = dr.minimum(x0 + 1, width - 1), dr.minimum(y0 + 1, height - 1)
        return [
            (y0 * width + x0, (1 - fx) * (1 - fy)),
            (y0 * width + x1, fx * (1 - fy)),
            (y1 * width + x0, (1 - fx) * fy),
            (y1 * width + x1, fx * fy),
        ]

    def _reflectance(self, si, light, view, active):
        sizes = self._spectra.sizes
        value = mi.UnpolarizedSpectrum(0.0)
        lows, fractions = [], []
        for channel in range(4):
            position = (si.wavelengths[channel] - self._first_nm) / self._step_nm
            low = dr.minimum(mi.UInt32(dr.maximum(position, 0.0)), sizes.last_band_pair)
            lows.append(low)
            fractions.append(dr.clip(position - mi.Float(low), 0.0, 1.0))
        combinations = [
            (light_index * sizes.views + view_index, light_weight * view_weight)
            for light_index, light_weight in self._corners(0, light)
            for view_index, view_weight in self._corners(1, view)
        ]
        texels = self._texels(si.uv)
        channels = self._spectra.blend(combinations, texels, lows, fractions, active)
        lobe = self._lobe(light, view, texels, active) if self._lobes is not None else 0.0
        for channel, sample in enumerate(channels):
            value[channel] = sample + lobe
        return value

    def _lobe(self, light, view, texels, active):
        """The texels' specular lobes (:func:`recon.btf.specular_lobe.microfacet_specular`) at
        ``light``, ``view``, blended like their residuals."""
        roughness, weight, beckmann = self._lobes
        half = dr.normalize(light + view)
        cos_h = dr.clip(half.z, 1e-9, 1.0)
        tan_h_squared = (1 - cos_h * cos_h) / (cos_h * cos_h)
        fresnel = mi.fresnel(dr.clip(dr.dot(light, half), 0.0, 1.0), COATING_IOR)[0]
        tangents = [
            dr.sqrt(dr.maximum(1 - w.z * w.z, 0.0)) / dr.maximum(w.z, 1e-9) for w in (light, view)
        ]
        total = mi.Float(0.0)
        for texel, texel_weight in texels:
            alpha = dr.gather(mi.Float, roughness, texel, active)
            scale = dr.gather(mi.Float, weight, texel, active)
            is_beckmann = dr.gather(mi.Float, beckmann, texel, active) > 0.5
            alpha_squared = alpha * alpha
            ggx = alpha_squared / (
                dr.pi * dr.square(cos_h * cos_h) * dr.square(alpha_squared + tan_h_squared)
            )
            gauss = dr.exp(-tan_h_squared / alpha_squared) / (
                dr.pi * alpha_squared * dr.square(cos_h * cos_h)
            )
            shadowing = mi.Float(1.0)
            for tangent in tangents:
                smith_ggx = 2 / (1 + dr.sqrt(1 + alpha_squared * tangent * tangent))
                a = 1 / dr.maximum(alpha * tangent, 1e-12)
                rational = (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a)
                smith_beckmann = dr.select(a >= 1.6, 1.0, rational)
                shadowing *= dr.select(is_beckmann, smith_beckmann, smith_ggx)
            distribution = dr.select(is_beckmann, gauss, ggx)
            total += texel_weight * scale * distribution * shadowing
        value = fresnel * total / (4 * light.z * view.z)
        return dr.select(active & (light.z > 0) & (view.z > 0), value, 0.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_view = mi.Frame3f.cos_theta(si.wi)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)
        active = active & (cos_view > 0) & (bs.pdf > 0)
        value = self._reflectance(si, bs.wo, si.wi, active) * dr.pi
        return bs, dr.select(active, value, 0.0)

    def eval(self, ctx, si, wo, active=True):
        cos_light = mi.Frame3f.cos_theta(wo)
        active = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (cos_light > 0)
        return dr.select(active, self._reflectance(si, wo, si.wi, active) * cos_light, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        active = active & (mi.Frame3f.cos_theta(si.wi) > 0)
        return dr.select(active, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def to_string(self):
        spectra = self._spectra
        _, rows, columns, _ = spectra.sizes.shape
        return f"SpectralBTF[{type(spectra).__name__}, {rows}x{columns}]"


register_once("spectral_btf", mi.register_bsdf, lambda props: SpectralBTF(props))
