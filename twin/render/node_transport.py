"""Light transport of a rig scene at wavelength nodes, with the spectra in closed form.

The rigs light a sample with one lamp (a point source, or a distant light for the truth), or
with LEDs that share one spectrum (the dome), and photograph it through narrow bands. Every
light path's contribution is a geometric factor times the spectral factors of the surfaces it
meets: a Lambertian base contributes its reflectance :math:`\\rho_k(\\lambda)`, the dielectric
coating of a glossy part (constant index 1.5) and a clear dielectric (a constant index) a factor
independent of wavelength, a metal its Fresnel reflectance. A clear dielectric's transmission is
traced on the camera's paths, but the lamps light nothing through it: a shadow ray stops at any
surface, as in Mitsuba's path tracer, which finds no caustics of point lights. The materials'
reflectances are designed on ``MATERIAL_GRID`` (380-780 nm every 5 nm, linear in between and
constant beyond, :mod:`twin.materials.builders`), so a path that meets one Lambertian surface is
exactly linear between those nodes.

:class:`NodeScene` therefore traces each path once and evaluates its spectrum at the 81 nodes:
Mitsuba's BSDFs give the geometric factors of each lobe (the parts carry stand-in BSDFs of unit
reflectance, :func:`twin.render.shapes.part_bsdf`), tables of the parts' reflectances at the
nodes give the spectral ones. A band's value is then an integral of the node values against the
band's response (:func:`node_weights`): exact for direct lighting, and within the product of two
piecewise-linear reflectances' curvature for light that meets two surfaces. Mitsuba's spectral
path tracer instead samples four wavelengths per path, so each of 33 bands sees an eighth of the
paths: tens of percent of Monte Carlo noise per pixel and band at 64 samples, where the nodes
leave none.

Lamps lit one at a time (the dome's LEDs) share the camera's paths: the random numbers jitter
the pixel and sample the bounce, whatever the lamp, so :meth:`NodeScene.transport_each` traces
the paths once, projects each vertex's spectral factors on the channels once and adds per lamp
only its shadow rays and the lobes' geometric factors, each lamp's image the one-lamp render's
with the same seed.

The integrator is matched to the scene: direct lighting by emitter sampling (one shadow ray to
the delta light; to every lamp of a group of point lights at the first surface, to one lamp
chosen at random after a bounce), the bounces by sampling the BSDF, pixel positions stratified
on a grid of :func:`twin.render.spectra.rendered_spp` samples. Random numbers come from a PCG32
stream per pixel and sample seeded by ``seed``: the same seed gives the same image whatever the
thread count and however the image is cut into kernel launches.

References
----------
- Jakob, W., Speierer, S., Roussel, N., et al. (2022). Mitsuba 3 renderer, version 3.x.
  https://mitsuba-renderer.org (BSDFs ``diffuse``, ``roughplastic`` with ``nonlinear=false``,
  ``roughconductor``, ``roughdielectric``; scene ray casts).
- Pharr, M., Jakob, W., Humphreys, G. (2016). Physically Based Rendering, 3rd ed., 14.2-14.5
  (direct lighting from point and distant lights; path tracing).
- The thesis, section 4.1.1 (the gonioreflectometer's camera and lamp) and Eq. 6.1 / 10.9
  (band values as integrals of radiance against the band's response).
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra, resample
from twin.materials.builders import MATERIAL_GRID
from twin.materials.surfaces import SurfacePart
from twin.render.render import load_scene
from twin.render.shapes import mitsuba_shape, part_bsdf
from twin.render.spectra import rendered_spp
from twin.render.variant import activate

__all__ = [
    "NODES_NM",
    "DistantLight",
    "NodeScene",
    "ParallelCamera",
    "PinholeRays",
    "PointLight",
    "PointLights",
    "node_weights",
]

NODES_NM = MATERIAL_GRID.wavelengths_nm
"""Wavelengths at which the transport is evaluated: the materials' design grid."""

_MAX_LANES = 1 << 20  # samples per kernel launch; larger renders run in passes
_LANE_VALUES = 1 << 22  # most per-lane values of transport_each's lamps summed at once
_EACH_LANES = 1 << 18  # samples per pass of transport_each (its bounce's node tables)
_EACH_FACTORS = 1 << 25  # most lamp factors of one lobe per pass (lamps x samples)


def node_weights(responses: SampledSpectra) -> np.ndarray:
    """Weights ``(n_nodes, n_channels)`` that turn node values into channel values.

    Entry :math:`(n, c)` is :math:`\\int R_c(\\lambda) \\phi_n(\\lambda) d\\lambda` for the
    hat functions :math:`\\phi_n` of the nodes (the first and last held constant beyond the
    nodes), integrated with the trapezoidal rule on the responses' grid: for a transport
    :math:`T(\\lambda)` linear between the nodes, ``T_nodes @ weights`` is
    :math:`\\int R_c T d\\lambda` (Eq. 6.1).
    """
    rows = np.atleast_2d(responses.values)
    wavelengths = responses.grid.wavelengths_nm
    hats = np.stack(
        [np.interp(wavelengths, NODES_NM, unit) for unit in np.eye(NODES_NM.size)]
    )  # (n_nodes, K)
    return (hats * responses.grid.quadrature_weights()) @ rows.T


@dataclass(frozen=True)
class PointLight:
    """An isotropic point lamp of unit intensity (W/sr per nm, every wavelength) at
    ``position_m`` in the scene's frame."""

    position_m: np.ndarray


@dataclass(frozen=True)
class PointLights:
    """Isotropic point lamps of unit intensity each (W/sr per nm, every wavelength) at the rows
    of ``positions_m`` ``(n, 3)`` in the scene's frame, lit together: the transport is the sum
    of theirs, every lamp sampled at every path vertex (no light-selection noise)."""

    positions_m: np.ndarray


@dataclass(frozen=True)
class DistantLight:
    """Unit irradiance (W/m^2 per nm, on a plane facing the light) arriving from
    ``direction`` (a unit vector pointing towards the light, scene frame)."""

    direction: np.ndarray


@dataclass(frozen=True)
class PinholeRays:
    """Rays of a pinhole camera in the scene's frame: ``origin_m`` and the unit vectors
    ``left``, ``up``, ``forward``; ``pixels`` across a square field of ``tan_half_fov``;
    ``window`` the centred pixels read out (default all).

    A continuous pixel position ``(column, row)`` maps as in
    :meth:`twin.render.scene.PinholeCamera.project`: direction
    ``forward + ((pixels/2 - column) left + (pixels/2 - row) up) / focal``.
    """

    origin_m: np.ndarray
    left: np.ndarray
    up: np.ndarray
    forward: np.ndarray
    tan_half_fov: float
    pixels: int
    window: int | None = None

    @property
    def shape(self) -> tuple[int, int]:
        side = self.window or self.pixels
        return side, side

    def rays(self, column, row):
        """Rays through the continuous pixel positions ``column``, ``row`` (Dr.Jit arrays)."""
        offset = (self.pixels - (self.window or self.pixels)) // 2
        focal = _scalar(self.pixels / 2 / self.tan_half_fov)
        centre = _scalar(self.pixels / 2 - offset)
        direction = (
            _vector(self.forward)
            + _vector(self.left) * ((centre - column) / focal)
            + _vector(self.up) * ((centre - row) / focal)
        )
        return mi.Ray3f(_vector(self.origin_m, mi.Point3f), dr.normalize(direction))


@dataclass(frozen=True)
class ParallelCamera:
    """Parallel rays along ``-view`` through the points ``(x, y, 0)`` of a square of half-size
    ``half_m`` on the sample plane: texel ``(row, column)`` covers
    ``x`` in ``-half + 2 half [column, column + 1] / texels`` and ``y`` in
    ``half - 2 half [row, row + 1] / texels`` (the rectified images of a measured BTF)."""

    view: np.ndarray
    half_m: float
    texels: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.texels, self.texels

    def rays(self, column, row):
        """Rays through the continuous texel positions ``column``, ``row`` (Dr.Jit arrays)."""
        scale = _scalar(2 * self.half_m / self.texels)
        half = _scalar(self.half_m)
        view = _vector(self.view)
        on_plane = mi.Point3f(column * scale - half, half - row * scale, 0.0)
        return mi.Ray3f(on_plane + 0.1 * view, -view)


def _vector(values: np.ndarray, kind=None):
    """A 3-vector as an opaque Dr.Jit value: a kernel input, not a constant compiled into the
    kernel, so that every view and light runs the same compiled kernel."""
    return dr.opaque(kind or mi.Vector3f, [float(value) for value in values])


def _scalar(value: float):
    """A number as an opaque Dr.Jit value (a kernel input, as :func:`_vector`)."""
    return dr.opaque(mi.Float, float(value))


def _texel_nodes(part: SurfacePart) -> np.ndarray:
    """A part's reflectance at the nodes, one row per texel ``(H * W, n_nodes)``."""
    spectra = part.reflectance if part.texture is None else part.texture
    nodes = resample(spectra, MATERIAL_GRID, out_of_range="clamp").values
    return nodes.reshape(-1, NODES_NM.size)


def _texel_index(uv, part, texels: dict, active):
    """Row of :attr:`NodeScene.reflectance` seen at texture coordinates ``uv`` of ``part``:
    the nearest texel (row 0 at v = 1), the part's only row where it has no texture."""
    height = dr.gather(mi.UInt32, texels["height"], part, active)
    width = dr.gather(mi.UInt32, texels["width"], part, active)
    column = mi.UInt32(dr.clip(uv.x, 0.0, 1.0) * mi.Float(width))
    row = mi.UInt32(dr.clip(1.0 - uv.y, 0.0, 1.0) * mi.Float(height))
    column, row = dr.minimum(column, width - 1), dr.minimum(row, height - 1)
    first = dr.gather(mi.UInt32, texels["first"], part, active)
    return first + row * width + column


def _conductor_index(part: SurfacePart) -> tuple[np.ndarray, np.ndarray]:
    """Real and imaginary index ``(n_nodes,)`` of a part's metal (Mitsuba's tabulated data)."""
    parameters = mi.traverse(load_scene(part_bsdf(part)))
    return tuple(
        np.interp(
            NODES_NM,
            np.asarray(parameters[f"{name}.wavelengths"], np.float64),
            np.asarray(parameters[f"{name}.values"], np.float64),
        )
        for name in ("eta", "k")
    )


def _lobes() -> list:
    """Contexts that evaluate a BSDF's diffuse lobe and its glossy lobes (the variant active)."""
    glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.GlossyTransmission
    return [
        mi.BSDFContext(mi.TransportMode.Radiance, int(flag))
        for flag in (mi.BSDFFlags.DiffuseReflection, glossy)
    ]


def _add_lanes(values: np.ndarray, pixels: np.ndarray, terms: list) -> None:
    """Add lanes' values to their pixels: ``values`` ``(n_lamps, n_pixels, n_channels)``
    gains, for each lane ``j`` and lamp ``l``, the sum over ``terms`` of ``factors[l, j]`` times
    ``channels[j]`` (each term a pair ``factors`` ``(n_lamps, n_lanes)``, ``channels``
    ``(n_lanes, n_channels)``) at pixel ``pixels[j]`` (in ascending order: a pixel's lanes are
    consecutive); lamps in groups of at most :data:`_LANE_VALUES` values. Only the pixels that
    have lanes are touched: each pixel's lanes are summed in order (``numpy.add.reduceat``)."""
    lamps, _, channels = values.shape
    if not pixels.size:
        return
    starts = np.flatnonzero(np.diff(pixels, prepend=pixels[0] - 1))
    rows = pixels[starts]
    group = max(1, _LANE_VALUES // max(1, pixels.size * channels))
    for first in range(0, lamps, group):
        chosen = slice(first, min(first + group, lamps))
        factors, values_per_lane = terms[0]
        per_lane = factors[chosen, :, None] * values_per_lane[None, :, :]
        for factors, values_per_lane in terms[1:]:
            per_lane += factors[chosen, :, None] * values_per_lane[None, :, :]
        values[chosen, rows] += np.add.reduceat(per_lane, starts, axis=1)


@dataclass
class _Vertex:
    """One surface interaction of each lane's path: where (``si``, its BSDF and part), which
    lanes reach it (``active``), the path's throughput to it and the reflectance there at the
    nodes (``n_nodes`` Dr.Jit values each), the row of :attr:`NodeScene.reflectance` seen
    (``texel``) and the lobes' weights (diffuse, glossy) of the bounce that led here (``None``
    at the first surface)."""

    si: object
    bsdf: object
    part: object
    active: object
    throughput: list
    rho: list
    texel: object
    bounce: list | None


@dataclass
class _Bounced:
    """A vertex after a bounce on the lanes that reach it (:meth:`NodeScene._bounced`): the
    vertex compacted to them, the channel values per unit light of its diffuse and glossy
    lobes ``(n_reached, n_channels)`` and the pixel of each lane ``(n_reached,)``."""

    vertex: _Vertex
    diffuse: np.ndarray
    glossy: np.ndarray
    pixels: np.ndarray


class NodeScene:
    """Surface parts as one Mitsuba scene of unit-reflectance BSDFs, with their spectral
    factors at the nodes (module docstring); built once, rendered from many views.

    Parameters
    ----------
    parts
        The scene's surfaces, in the frame that cameras and lights are given in.
    """

    def __init__(self, parts: Sequence[SurfacePart]):
        if not parts:
            raise InputError("parts: expected at least one surface part")
        activate()
        unit_bsdfs: dict[str, object] = {}  # parts with the same lobes share one BSDF
        entries: dict[str, object] = {"type": "scene"}
        for part in parts:
            unit = part_bsdf(part, unit=True)
            key = json.dumps(unit, sort_keys=True)
            if key not in unit_bsdfs:
                unit_bsdfs[key] = load_scene(unit)
            entries[part.name] = mitsuba_shape(part, bsdf=unit_bsdfs[key])
        self._scene = load_scene(entries)
        names = [part.name for part in parts]
        registry = np.asarray(dr.reinterpret_array(mi.UInt32, self._scene.shapes_dr()))
        part_of = np.zeros(int(registry.max()) + 1, np.uint32)
        for registered, shape in zip(registry, self._scene.shapes(), strict=True):
            part_of[registered] = names.index(shape.id())
        self._part_of = part_of
        self.reflectance = np.concatenate([_texel_nodes(part) for part in parts])
        """Lambertian reflectance at the nodes ``(n_texels, n_nodes)``: each part's texels in
        turn (one for a part of one reflectance)."""
        sizes = np.array([part.texels for part in parts], np.uint32)  # (n_parts, 2): H, W
        counts = sizes.prod(axis=1)
        self._texels = {
            "first": (np.cumsum(counts) - counts).astype(np.uint32),
            "height": sizes[:, 0],
            "width": sizes[:, 1],
        }
        self._metal_index = None
        if any(part.conductor is not None for part in parts):
            eta = np.zeros((len(parts), NODES_NM.size))
            k = np.zeros_like(eta)
            for index, part in enumerate(parts):
                if part.conductor is not None:
                    eta[index], k[index] = _conductor_index(part)
            self._metal_index = eta, k, np.array([p.conductor is not None for p in parts])

    @property
    def has_metal(self) -> bool:
        """Whether a part is a metal: :meth:`transport_each` then renders lamp by lamp."""
        return self._metal_index is not None

    def transport(
        self,
        camera: PinholeRays | ParallelCamera,
        light: PointLight | PointLights | DistantLight,
        *,
        spp: int = 4,
        seed: int = 0,
        bounces: int = 1,
    ) -> np.ndarray:
        """Radiance at the nodes ``(H, W, n_nodes)`` (per unit intensity or irradiance of the
        light) averaged over each pixel.

        Parameters
        ----------
        camera
            Where the rays start and go (:class:`PinholeRays`, :class:`ParallelCamera`).
        light
            The scene's light (or lights of one spectrum, :class:`PointLights`).
        spp
            Samples per pixel, stratified: rounded up to a power of 4
            (:func:`twin.render.spectra.rendered_spp`).
        seed
            Seed of the random numbers; the same seed gives the same image.
        bounces
            Surface interactions after the first that light may take (1: Mitsuba's
            ``path`` integrator at ``max_depth`` 3).
        """
        if bounces < 0:
            raise InputError(f"bounces: expected 0 or more, got {bounces}")
        samples = rendered_spp(spp)
        height, width = camera.shape
        per_launch = max(1, _MAX_LANES // samples)
        radiance = [
            self._render_pixels(camera, light, seed, bounces, first, per_launch, samples)
            for first in range(0, height * width, per_launch)
        ]
        return np.concatenate(radiance).reshape(height, width, NODES_NM.size)

    def transport_each(
        self,
        camera: PinholeRays | ParallelCamera,
        positions_m: np.ndarray,
        weights: np.ndarray,
        *,
        spp: int = 4,
        seed: int = 0,
        bounces: int = 1,
        channels: Sequence[Sequence[int]] | None = None,
    ) -> np.ndarray:
        """Channel values ``(n_lamps, H, W, n_channels)`` of each point lamp at the rows of
        ``positions_m`` ``(n_lamps, 3)`` lit alone, the node radiance projected on ``weights``
        ``(n_nodes, n_channels)`` (:func:`node_weights`).

        The camera's paths are traced once for all the lamps: light transport is linear in the
        light, and the paths of :meth:`transport` with one :class:`PointLight` do not depend on
        where the lamp is (its random numbers jitter the pixel and sample the bounce only). Per
        path vertex the spectral factors are projected on the channels once (the diffuse lobe's
        throughput times reflectance, the glossy lobe's throughput); each lamp then adds only
        its shadow rays and the lobes' geometric factors. Lamp ``i``'s values equal
        ``transport(camera, PointLight(positions_m[i]), spp=spp, seed=seed) @ weights`` to float
        rounding (``tests/twin/render/test_node_transport.py``). A scene with a metal, whose
        glossy spectrum depends on the light's direction, renders lamp by lamp
        (:meth:`transport` with the same seed: the same values).

        Parameters
        ----------
        camera, spp, seed, bounces
            As for :meth:`transport`.
        positions_m
            The lamps, one row each, in the scene's frame.
        weights
            Node weights of the channels (the channels' responses times the lamps' spectrum).
        channels
            Per lamp, the channels wanted (indices into ``weights``' columns): lamp ``i``'s
            values are then ``(H, W, k)`` in its first ``k = len(channels[i])`` entries, in that
            order (the rest zero; ``n_channels`` is the longest list's length). Default: all.
        """
        if bounces < 0:
            raise InputError(f"bounces: expected 0 or more, got {bounces}")
        positions = np.asarray(positions_m, np.float64).reshape(-1, 3)
        weights = np.asarray(weights, np.float32).reshape(NODES_NM.size, -1)
        wanted = (
            [tuple(range(weights.shape[1]))] * len(positions)
            if channels is None
            else [tuple(int(c) for c in chosen) for chosen in channels]
        )
        if len(wanted) != len(positions):
            raise InputError(
                f"channels: expected one list per lamp ({len(positions)}), got {len(wanted)}"
            )
        height, width = camera.shape
        if self.has_metal:
            values = np.zeros((len(positions), height, width, max(map(len, wanted))), np.float32)
            for lamp, (position, chosen) in enumerate(zip(positions, wanted, strict=True)):
                alone = self.transport(
                    camera, PointLight(position), spp=spp, seed=seed, bounces=bounces
                )
                values[lamp, ..., : len(chosen)] = alone.astype(np.float32) @ weights[:, chosen]
            return values
        samples = rendered_spp(spp)
        per_launch = max(1, min(_EACH_LANES, _EACH_FACTORS // len(positions)) // samples)
        values = np.empty((len(positions), height * width, max(map(len, wanted))), np.float32)
        projected = self.reflectance.astype(np.float32) @ weights  # (n_texels, n_channels)
        for first in range(0, height * width, per_launch):
            count = min(per_launch, height * width - first)
            self._each_pixels(
                camera,
                positions,
                (weights, projected, wanted),
                (seed, bounces, samples),
                first,
                values[:, first : first + count],
            )
        return values.reshape(len(positions), height, width, -1)

    def _each_pixels(self, camera, positions, channels, trace, first, out) -> None:
        """:meth:`transport_each` of the pixels from flat index ``first`` on, written into
        ``out`` ``(n_lamps, count, n_channels)``; ``channels`` is ``(weights, projected,
        wanted)`` (``projected``: the reflectance table projected on the channels, ``(n_texels,
        n_channels)``), ``trace`` is ``(seed, bounces, samples)``.

        At the first surface the diffuse lobe's channel values are the texel's reflectance
        projected on the channels (a table) and the glossy lobe's the channels' sums; each
        pixel's samples mostly see one texel (the first sample's), so a pixel's values are the
        sums of the lamps' factors times the first sample's texel, plus for the samples on
        another texel the difference of the two. After a bounce only the lanes still on the
        scene are kept, with their throughput at the nodes; each lamp's factors there are summed
        into the pixels that have such lanes (:func:`_add_lanes`). Lamps that want the same
        channels are combined together; a lobe whose factors are zero everywhere (no glossy
        part in sight) adds nothing and is skipped."""
        weights, projected, wanted = channels
        seed, bounces, samples = trace
        count = out.shape[1]
        _, rng, ray = self._lanes(camera, seed, first, count, samples)
        table = self.reflectance.astype(np.float32)
        vertices = list(self._walk(ray, rng, bounces))
        first_vertex = vertices[0]
        dr.eval(
            first_vertex.si,
            first_vertex.bsdf,
            first_vertex.part,
            first_vertex.active,
            first_vertex.texel,
        )
        texel = np.asarray(first_vertex.texel)
        bounced = self._bounced(vertices, table, weights, texel, samples)
        lamps = mi.Float(np.asarray(positions, np.float32).ravel())
        diffuse, glossy = self._lamp_factors(first_vertex, lamps)
        # (n_lamps, pixels): the factors summed over each pixel's samples
        diffuse_sum, glossy_sum = (
            np.asarray(dr.block_sum(table_, samples)).reshape(len(positions), count)
            for table_ in (diffuse, glossy)
        )
        texel = texel.reshape(count, samples)
        reference = projected[texel[:, 0]]
        pixel, sample = np.nonzero(texel != texel[:, :1])
        difference = projected[texel[pixel, sample]] - reference[pixel]
        edge_lane = (pixel * samples + sample).astype(np.uint32)
        lanes = count * samples
        edge = np.asarray(  # (n_lamps, n_edge_lanes): the diffuse factors of those samples
            dr.gather(
                mi.Float,
                diffuse,
                mi.UInt32(
                    (
                        np.arange(len(positions), dtype=np.uint32)[:, None] * lanes + edge_lane
                    ).ravel()
                ),
            )
        ).reshape(len(positions), -1)
        later = [
            [
                np.asarray(factors).reshape(len(positions), -1)
                for factors in self._lamp_factors(after.vertex, lamps)
            ]
            for after in bounced
        ]
        groups: dict[tuple[int, ...], list[int]] = {}
        for lamp, chosen in enumerate(wanted):
            groups.setdefault(chosen, []).append(lamp)
        whole = len(groups) == 1 and len(wanted[0]) == out.shape[2]
        if not whole:
            out.fill(0)
        glossy_seen = bool(glossy_sum.any())
        for chosen, members in groups.items():
            ks = list(chosen)
            lamp_rows = slice(None) if len(members) == len(wanted) else np.array(members)
            part = out if whole else np.empty((len(members), count, len(ks)), np.float32)
            np.multiply(diffuse_sum[lamp_rows, :, None], reference[None, :, ks], out=part)
            if glossy_seen:
                part += glossy_sum[lamp_rows, :, None] * weights[:, ks].sum(axis=0)
            _add_lanes(part, pixel, [(edge[lamp_rows], difference[:, ks])])
            for after, (after_diffuse, after_glossy) in zip(bounced, later, strict=True):
                terms = [(after_diffuse[lamp_rows], after.diffuse[:, ks])]
                if after_glossy.any():
                    terms.append((after_glossy[lamp_rows], after.glossy[:, ks]))
                _add_lanes(part, after.pixels, terms)
            if not whole:
                out[lamp_rows, :, : len(ks)] = part
        out *= np.float32(1 / samples)

    def _lamp_factors(self, vertex, lamps):
        """The diffuse and glossy lobes' geometric factors at ``vertex`` for each lamp of
        ``lamps`` (flat positions), visibility included: two evaluated Dr.Jit tables of
        ``n_lamps x lanes``, lamp-major. One kernel loops over the lamps."""
        lobes = _lobes()
        width = dr.width(vertex.active)
        count = dr.width(lamps) // 3
        diffuse_out = dr.empty(mi.Float, count * width)  # the loop writes every entry
        glossy_out = dr.empty(mi.Float, count * width)
        lane = dr.arange(mi.UInt32, width)

        def add_lamp(index):
            position = dr.gather(mi.Point3f, lamps, index)
            diffuse, glossy = self._lit(
                vertex.si, vertex.bsdf, vertex.part, vertex.active, lobes, position=position
            )
            dr.scatter(diffuse_out, diffuse, index * width + lane)
            dr.scatter(glossy_out, glossy[0], index * width + lane)
            return (index + 1,)

        total = dr.opaque(mi.UInt32, count)
        dr.while_loop(
            (dr.zeros(mi.UInt32, width),), lambda index: index < total, add_lamp, label="each"
        )
        dr.eval(diffuse_out, glossy_out)
        return diffuse_out, glossy_out

    def _bounced(self, vertices, table, weights, texel, samples) -> list[_Bounced]:
        """The vertices after the first, each on the lanes that reach it: their throughput at
        the nodes (the product of the bounces' lobe weights and reflectances), the channel
        values of their lobes per unit light and each lane's pixel."""
        bounced = []
        reached = np.arange(texel.size)
        throughput = np.ones((texel.size, 1), np.float32)
        for vertex in vertices[1:]:
            # one kernel traces the bounce for everything read of it below
            dr.eval(vertex.active, vertex.bounce, vertex.texel, vertex.si, vertex.part)
            active = np.asarray(vertex.active)
            keep = active[reached]
            diffuse_weight, glossy_weight = (np.asarray(w)[reached[keep]] for w in vertex.bounce)
            throughput = throughput[keep] * (
                diffuse_weight[:, None] * table[texel[reached[keep]]] + glossy_weight[:, None]
            )
            reached = reached[keep]
            if not reached.size:  # every path has left the scene
                break
            texel = np.asarray(vertex.texel)
            index = mi.UInt32(reached.astype(np.uint32))
            si = dr.gather(type(vertex.si), vertex.si, index)
            part = dr.gather(mi.UInt32, vertex.part, index)
            compact = _Vertex(
                si, si.bsdf(), part, dr.full(mi.Bool, True, reached.size), [], [], None, None
            )
            dr.eval(compact.si, compact.bsdf, compact.part, compact.active)
            bounced.append(
                _Bounced(
                    compact,
                    (throughput * table[texel[reached]]) @ weights,
                    throughput @ weights,
                    reached // samples,
                )
            )
        return bounced

    def _lanes(self, camera, seed, first, count, samples):
        """The lanes of ``samples`` stratified samples in each of ``count`` pixels from flat
        index ``first`` on: each lane's pixel slot, the random numbers (a PCG32 stream that
        depends on the seed, the pixel and the sample's index alone) and the camera ray."""
        height, width = camera.shape
        lane = dr.arange(mi.UInt32, count * samples)
        slot = lane // samples
        sample = lane - slot * samples
        pixel = slot + dr.opaque(mi.UInt32, first)
        row = pixel // width
        column = pixel - row * width
        # PCG32's constructor offsets each lane's state and stream by its index in the launch,
        # which would tie the numbers to how the image is cut into launches (the pixels per
        # launch of transport_each depend on its lamps): seed with the lane's index in the
        # whole image instead (the same numbers as before in a launch from pixel 0)
        index = mi.UInt64(pixel) * samples + mi.UInt64(sample)
        rng = mi.PCG32(size=dr.width(lane))
        rng.seed(initstate=index + index, initseq=dr.opaque(mi.UInt64, seed) + index)
        strata = int(round(np.sqrt(samples)))
        stratum_x = mi.Float(sample % strata)
        stratum_y = mi.Float(sample // strata)
        ray = camera.rays(
            mi.Float(column) + (stratum_x + rng.next_float32()) / strata,
            mi.Float(row) + (stratum_y + rng.next_float32()) / strata,
        )
        return slot, rng, ray

    def _render_pixels(self, camera, light, seed, bounces, first, count, samples) -> np.ndarray:
        """Mean node radiance ``(n, n_nodes)`` of ``samples`` stratified samples in each of the
        ``count`` pixels (fewer at the image's end) from flat index ``first`` on."""
        height, width = camera.shape
        count = min(count, height * width - first)
        slot, rng, ray = self._lanes(camera, seed, first, count, samples)
        nodes = self._trace(ray, light, rng, bounces)
        means = dr.zeros(mi.Float, count * NODES_NM.size)
        for n, value in enumerate(nodes):
            dr.scatter_add(means, value * (1.0 / samples), slot * NODES_NM.size + n)
        return np.asarray(means).reshape(count, NODES_NM.size)

    def _walk(self, ray, rng, bounces) -> Iterator[_Vertex]:
        """The vertices of each lane's path, first surface first; the bounce after a vertex is
        sampled when the caller asks for the next one (so that the caller's random numbers for
        the vertex's light come first)."""
        scene = self._scene
        part_of = mi.UInt32(self._part_of)
        reflectance = mi.Float(self.reflectance.ravel().astype(np.float32))
        texels = {name: mi.UInt32(values) for name, values in self._texels.items()}
        count = NODES_NM.size
        lobes = _lobes()
        throughput = [mi.Float(1.0) for _ in range(count)]
        si = scene.ray_intersect(ray)
        active = si.is_valid()
        weight = None
        for depth in range(bounces + 1):
            shape_ids = dr.reinterpret_array(mi.UInt32, si.shape)
            # Mitsuba's stub leaves reinterpret_array's result untyped (object)
            part = dr.gather(mi.UInt32, part_of, shape_ids, active)  # type: ignore[arg-type]
            texel = _texel_index(si.uv, part, texels, active)
            rho = [
                dr.gather(mi.Float, reflectance, texel * count + n, active) for n in range(count)
            ]
            bsdf = si.bsdf()
            yield _Vertex(si, bsdf, part, active, throughput, rho, texel, weight)
            if depth == bounces:
                return
            sampled, _ = bsdf.sample(
                mi.BSDFContext(),
                si,
                rng.next_float32(),
                mi.Point2f(rng.next_float32(), rng.next_float32()),
                active,
            )
            # new values, not in-place updates: the vertices yielded keep theirs
            active = active & (sampled.pdf > 0)
            weight = [
                dr.select(active, bsdf.eval(ctx, si, sampled.wo, active)[0] / sampled.pdf, 0.0)
                for ctx in lobes
            ]
            glossy = self._glossy_spectrum(si, sampled.wo, part, active) or [1.0]
            throughput = [
                value * (weight[0] * rho[n] + weight[1] * glossy[min(n, len(glossy) - 1)])
                for n, value in enumerate(throughput)
            ]
            si = scene.ray_intersect(si.spawn_ray(si.to_world(sampled.wo)), active)
            active = active & si.is_valid()

    def _trace(self, ray, light, rng, bounces) -> list:
        """Node radiance of each lane's path (list of ``n_nodes`` Float arrays)."""
        lobes = _lobes()
        radiance = [mi.Float(0.0) for _ in range(NODES_NM.size)]
        for depth, vertex in enumerate(self._walk(ray, rng, bounces)):
            chooser = rng if depth > 0 else None  # light after a bounce: one lamp of a group
            diffuse, glossy = self._direct(
                vertex.si, vertex.bsdf, vertex.part, light, vertex.active, lobes, chooser
            )
            for n, (throughput, rho) in enumerate(zip(vertex.throughput, vertex.rho, strict=True)):
                radiance[n] += throughput * (diffuse * rho + glossy[min(n, len(glossy) - 1)])
        return radiance

    def _direct(self, si, bsdf, part, light, active, lobes, chooser=None):
        """Light arriving straight from the lamps, summed over them: the diffuse lobe's
        geometric factor and the glossy lobe's value at the nodes (one value for all nodes
        where no metal is in the scene). With a random ``chooser`` (PCG32) a group of
        :class:`PointLights` is sampled by one lamp chosen uniformly, its light times their
        number: unbiased, for the weak light after a bounce."""
        if isinstance(light, DistantLight):
            return self._lit(si, bsdf, part, active, lobes, direction=_vector(light.direction))
        if isinstance(light, PointLight):
            position = _vector(light.position_m, mi.Point3f)
            return self._lit(si, bsdf, part, active, lobes, position=position)
        positions = mi.Float(np.asarray(light.positions_m, np.float32).ravel())
        lamps = dr.opaque(mi.UInt32, len(light.positions_m))
        if chooser is not None:
            index = dr.minimum(mi.UInt32(chooser.next_float32() * mi.Float(lamps)), lamps - 1)
            position = dr.gather(mi.Point3f, positions, index)
            diffuse, glossy = self._lit(si, bsdf, part, active, lobes, position=position)
            scale = mi.Float(lamps)
            return diffuse * scale, [value * scale for value in glossy]

        def add_lamp(index, diffuse, glossy):
            position = dr.gather(mi.Point3f, positions, index)
            lit_diffuse, lit_glossy = self._lit(si, bsdf, part, active, lobes, position=position)
            summed = [a + b for a, b in zip(glossy, lit_glossy, strict=True)]
            return index + 1, diffuse + lit_diffuse, summed

        width = dr.width(active)
        nodes = 1 if self._metal_index is None else NODES_NM.size
        state = (dr.zeros(mi.UInt32, width), dr.zeros(mi.Float, width))
        state += ([dr.zeros(mi.Float, width) for _ in range(nodes)],)
        _, diffuse, glossy = dr.while_loop(
            state, lambda index, *_: index < lamps, add_lamp, label="lamps"
        )
        return diffuse, glossy

    def _lit(self, si, bsdf, part, active, lobes, *, position=None, direction=None):
        """:meth:`_direct` of one lamp: a point lamp at ``position`` (factor the inverse square
        distance) or a distant one towards ``direction`` (factor one), if visible."""
        if position is not None:
            offset = position - si.p
            distance_squared = dr.squared_norm(offset)
            direction = offset * dr.rsqrt(distance_squared)
            shadow, factor = si.spawn_ray_to(position), dr.rcp(distance_squared)
        else:
            shadow, factor = si.spawn_ray(direction), 1.0
        visible = active & ~self._scene.ray_test(shadow, active)
        to_light = si.to_local(direction)
        diffuse, glossy = (
            dr.select(visible, bsdf.eval(ctx, si, to_light, visible)[0], 0.0) * factor
            for ctx in lobes
        )
        spectrum = self._glossy_spectrum(si, to_light, part, active)
        return diffuse, [glossy * value for value in spectrum] if spectrum else [glossy]

    def _glossy_spectrum(self, si, wo, part, active) -> list | None:
        """Spectral factor of the glossy lobe at the nodes: one for a dielectric, the
        Fresnel reflectance at the half vector for a metal (as Mitsuba's ``roughconductor``);
        ``None`` (one at every node) in a scene without metal."""
        if self._metal_index is None:
            return None

        eta, k, is_metal = self._metal_index
        count = NODES_NM.size
        metal = dr.gather(mi.UInt32, mi.UInt32(is_metal.astype(np.uint32)), part, active) > 0
        cosine = dr.dot(si.wi, dr.normalize(si.wi + wo))
        eta_table = mi.Float(eta.ravel().astype(np.float32))
        k_table = mi.Float(k.ravel().astype(np.float32))
        spectrum = []
        for n in range(count):
            index = part * count + n
            complex_index = mi.Complex2f(  # type: ignore[operator]  # a variant's type, not in the stub
                dr.gather(mi.Float, eta_table, index, active),
                dr.gather(mi.Float, k_table, index, active),
            )
            spectrum.append(dr.select(metal, mi.fresnel_conductor(cosine, complex_index), 1.0))
        return spectrum
