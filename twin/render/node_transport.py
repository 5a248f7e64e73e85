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

The integrator is matched to the scene: direct lighting by emitter sampling (one shadow ray to
the delta light; to every lamp of a group of point lights at the first surface, to one lamp
chosen at random after a bounce), the bounces by sampling the BSDF, pixel positions stratified
on a grid of :func:`twin.render.spectra.rendered_spp` samples. Random numbers come from a PCG32
stream per pixel seeded by ``seed``: the same seed gives the same image whatever the thread
count.

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
from collections.abc import Sequence
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from recon.errors import SpectwinInputError
from recon.spectra import SampledSpectra, resample
from twin.materials.builders import MATERIAL_GRID
from twin.materials.surfaces import SurfacePart
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
    parameters = mi.traverse(mi.load_dict(part_bsdf(part)))
    return tuple(
        np.interp(
            NODES_NM,
            np.asarray(parameters[f"{name}.wavelengths"], np.float64),
            np.asarray(parameters[f"{name}.values"], np.float64),
        )
        for name in ("eta", "k")
    )


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
            raise SpectwinInputError("parts: expected at least one surface part")
        activate()
        unit_bsdfs: dict[str, object] = {}  # parts with the same lobes share one BSDF
        entries: dict[str, object] = {"type": "scene"}
        for part in parts:
            unit = part_bsdf(part, unit=True)
            key = json.dumps(unit, sort_keys=True)
            if key not in unit_bsdfs:
                unit_bsdfs[key] = mi.load_dict(unit)
            entries[part.name] = mitsuba_shape(part, bsdf=unit_bsdfs[key])
        self._scene = mi.load_dict(entries)
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
            raise SpectwinInputError(f"bounces: expected 0 or more, got {bounces}")
        samples = rendered_spp(spp)
        height, width = camera.shape
        per_launch = max(1, _MAX_LANES // samples)
        radiance = [
            self._render_pixels(camera, light, seed, bounces, first, per_launch, samples)
            for first in range(0, height * width, per_launch)
        ]
        return np.concatenate(radiance).reshape(height, width, NODES_NM.size)

    def _render_pixels(self, camera, light, seed, bounces, first, count, samples) -> np.ndarray:
        """Mean node radiance ``(n, n_nodes)`` of ``samples`` stratified samples in each of the
        ``count`` pixels (fewer at the image's end) from flat index ``first`` on. The random
        numbers of a sample depend on the seed, the pixel and the sample's index alone."""
        height, width = camera.shape
        count = min(count, height * width - first)
        lane = dr.arange(mi.UInt32, count * samples)
        slot = lane // samples
        sample = lane - slot * samples
        pixel = slot + dr.opaque(mi.UInt32, first)
        row = pixel // width
        column = pixel - row * width
        rng = mi.PCG32(
            size=dr.width(lane),
            initstate=mi.UInt64(pixel) * samples + mi.UInt64(sample),
            initseq=dr.opaque(mi.UInt64, seed),
        )
        strata = int(round(np.sqrt(samples)))
        stratum_x = mi.Float(sample % strata)
        stratum_y = mi.Float(sample // strata)
        ray = camera.rays(
            mi.Float(column) + (stratum_x + rng.next_float32()) / strata,
            mi.Float(row) + (stratum_y + rng.next_float32()) / strata,
        )
        nodes = self._trace(ray, light, rng, bounces)
        means = dr.zeros(mi.Float, count * NODES_NM.size)
        for n, value in enumerate(nodes):
            dr.scatter_add(means, value * (1.0 / samples), slot * NODES_NM.size + n)
        return np.asarray(means).reshape(count, NODES_NM.size)

    def _trace(self, ray, light, rng, bounces) -> list:
        """Node radiance of each lane's path (list of ``n_nodes`` Float arrays)."""
        scene = self._scene
        part_of = mi.UInt32(self._part_of)
        reflectance = mi.Float(self.reflectance.ravel().astype(np.float32))
        texels = {name: mi.UInt32(values) for name, values in self._texels.items()}
        count = NODES_NM.size
        glossy_lobes = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.GlossyTransmission
        lobes = [
            mi.BSDFContext(mi.TransportMode.Radiance, int(flag))
            for flag in (mi.BSDFFlags.DiffuseReflection, glossy_lobes)
        ]
        radiance = [mi.Float(0.0) for _ in range(count)]
        throughput = [mi.Float(1.0) for _ in range(count)]
        si = scene.ray_intersect(ray)
        active = si.is_valid()
        for depth in range(bounces + 1):
            part = dr.gather(mi.UInt32, part_of, dr.reinterpret_array(mi.UInt32, si.shape), active)
            texel = _texel_index(si.uv, part, texels, active)
            rho = [
                dr.gather(mi.Float, reflectance, texel * count + n, active) for n in range(count)
            ]
            bsdf = si.bsdf()
            chooser = rng if depth > 0 else None  # light after a bounce: one lamp of a group
            diffuse, glossy = self._direct(si, bsdf, part, light, active, lobes, chooser)
            for n in range(count):
                radiance[n] += throughput[n] * (diffuse * rho[n] + glossy[min(n, len(glossy) - 1)])
            if depth == bounces:
                break
            sampled, _ = bsdf.sample(
                mi.BSDFContext(),
                si,
                rng.next_float32(),
                mi.Point2f(rng.next_float32(), rng.next_float32()),
                active,
            )
            active &= sampled.pdf > 0
            weight = [
                dr.select(active, bsdf.eval(ctx, si, sampled.wo, active)[0] / sampled.pdf, 0.0)
                for ctx in lobes
            ]
            glossy = self._glossy_spectrum(si, sampled.wo, part, active) or [1.0]
            for n in range(count):
                throughput[n] *= weight[0] * rho[n] + weight[1] * glossy[min(n, len(glossy) - 1)]
            si = scene.ray_intersect(si.spawn_ray(si.to_world(sampled.wo)), active)
            active &= si.is_valid()
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
            complex_index = mi.Complex2f(
                dr.gather(mi.Float, eta_table, index, active),
                dr.gather(mi.Float, k_table, index, active),
            )
            spectrum.append(dr.select(metal, mi.fresnel_conductor(cosine, complex_index), 1.0))
        return spectrum
