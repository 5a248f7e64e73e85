"""A spectral environment map emitter for Mitsuba (Python plugin ``spectral_envmap``).

Mitsuba's built-in ``envmap`` is RGB only (ARCHITECTURE.md, "Mitsuba notes"); the thesis's
Figure 4.6 lights BTFs with a *spectral* environment map captured with the spectral camera
(section 4.2). The map is a lat-long image ``(H, W, K)`` of radiance in W m^-2 sr^-1 nm^-1 on a
regular wavelength grid: row ``r`` covers polar angles ``[r, r + 1] pi / H`` from the map's +z
axis, column ``c`` azimuths ``[c, c + 1] 2 pi / W`` from +x towards +y; radiance is constant
over a pixel (the texel a camera measured), linear in wavelength between bands and constant
beyond the first and last band (a camera band's passband reaches past its centre).

Importance sampling picks a pixel with probability proportional to its band-mean radiance times
its solid angle :math:`\\Omega_p = \\frac{2\\pi}{W}(\\cos\\theta_r - \\cos\\theta_{r+1})` and a
direction uniformly in solid angle within it, so the density is
:math:`p(\\omega) = P(p) / \\Omega_p`; with ``importance=False`` directions are uniform on the
sphere (for comparison). Maps are handed to Mitsuba by key (:func:`register_map`), because plugin
properties cannot carry arrays.

Importing this module activates the Mitsuba variant (:func:`twin.render.variant.activate`):
:class:`SpectralEnvmapEmitter` derives from the variant's ``mi.Emitter`` and is registered with
Mitsuba at import (:mod:`twin.render.plugins.registry`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.render.plugins.registry import PluginData, register_once
from twin.render.variant import activate

__all__ = ["SpectralEnvmapEmitter", "SpectralMap", "register_map", "spectral_envmap"]

# mi.Emitter below is the active variant's class: choose the variant before defining the plugin.
activate()

_MAPS = PluginData("map")


@dataclass(frozen=True)
class SpectralMap:
    """A lat-long spectral radiance map ``(H, W, K)`` on a regular grid (module docstring)."""

    radiance: np.ndarray
    grid: WavelengthGrid

    def __post_init__(self) -> None:
        values = np.asarray(self.radiance, np.float64)
        if values.ndim != 3 or values.shape[2] != self.grid.size or min(values.shape[:2]) < 1:
            raise InputError(
                f"radiance: expected a lat-long map (H, W, {self.grid.size}), got {values.shape}"
            )
        if not np.all(np.isfinite(values)) or np.any(values < 0):
            raise InputError("radiance: expected finite, non-negative radiance")
        steps = np.diff(self.grid.wavelengths_nm)
        if steps.size and not np.allclose(steps, steps[0]):
            raise InputError("grid: expected a regular wavelength grid (resample first)")

    def solid_angles(self) -> np.ndarray:
        """``(H, W)`` solid angle of every pixel, sr (they sum to 4 pi)."""
        height, width = self.radiance.shape[:2]
        edges = np.cos(np.linspace(0.0, np.pi, height + 1))
        return np.repeat(((edges[:-1] - edges[1:]) * 2 * np.pi / width)[:, None], width, axis=1)


def register_map(spectral_map: SpectralMap) -> str:
    """Keep ``spectral_map`` for the plugin and return the key to put in the scene dict."""
    return _MAPS.keep(spectral_map)


def spectral_envmap(spectral_map: SpectralMap, *, importance: bool = True) -> dict[str, object]:
    """Scene-dict entry of the emitter for ``spectral_map``.

    Parameters
    ----------
    spectral_map : SpectralMap
        The lat-long radiance map.
    importance : bool, optional
        Sample directions in proportion to the map's radiance (default) or uniformly.

    Returns
    -------
    dict
        The ``spectral_envmap`` entry for ``mi.load_dict``; the map is kept for the plugin by key.
    """
    return {"type": "spectral_envmap", "map": register_map(spectral_map), "importance": importance}


class SpectralEnvmapEmitter(mi.Emitter):
    """The ``spectral_envmap`` emitter: a lat-long spectral radiance map (module docstring).

    Parameters
    ----------
    props : mitsuba.Properties
        ``map``: the key of the map (:func:`register_map`); ``importance``: sample directions in
        proportion to radiance (default ``True``).
    """

    def __init__(self, props):
        super().__init__(props)
        spectral_map = _MAPS[props["map"]]
        self.m_flags = mi.EmitterFlags.Infinite | mi.EmitterFlags.SpatiallyVarying
        height, width, bands = spectral_map.radiance.shape
        self._height, self._width, self._bands = height, width, bands
        # the map's sizes enter the kernels as opaque values, not literals: a map of another
        # size reuses the compiled kernels (the same single-precision values as the literals)
        self._last_row, self._last_column = (dr.opaque(mi.UInt32, n - 1) for n in (height, width))
        self._columns, self._band_count = dr.opaque(mi.UInt32, width), dr.opaque(mi.UInt32, bands)
        self._last_band_pair = dr.opaque(mi.UInt32, max(bands - 2, 0))
        self._rows_per_radian = dr.opaque(mi.Float, height / math.pi)
        self._columns_per_radian = dr.opaque(mi.Float, width / (2 * math.pi))
        self._row_radians = dr.opaque(mi.Float, math.pi / height)
        self._column_radians = dr.opaque(mi.Float, 2 * math.pi / width)
        wavelengths = spectral_map.grid.wavelengths_nm
        self._first_nm = float(wavelengths[0])
        self._step_nm = float(wavelengths[1] - wavelengths[0]) if bands > 1 else 1.0
        self._span_nm = dr.opaque(mi.Float, self._step_nm * max(bands - 1, 1))
        self._radiance = mi.Float(spectral_map.radiance.astype(np.float32).ravel())
        weights = spectral_map.radiance.mean(axis=2) * spectral_map.solid_angles()
        if not weights.sum() > 0:
            raise InputError("radiance: the map emits nothing")
        self._distribution = mi.DiscreteDistribution(mi.Float(weights.ravel()))
        self._importance = bool(props.get("importance", True))
        self._radius = dr.opaque(mi.Float, 1e4)

    def set_scene(self, scene):
        sphere = scene.bbox().bounding_sphere()
        self._radius = dr.opaque(mi.Float, max(float(dr.max(sphere.radius)), 1e-3) * 2.0)

    def _pixel(self, direction):
        theta = dr.acos(dr.clip(direction.z, -1.0, 1.0))
        phi = dr.atan2(direction.y, direction.x)
        phi = dr.select(phi < 0, phi + 2 * dr.pi, phi)
        row = dr.minimum(mi.UInt32(theta * self._rows_per_radian), self._last_row)
        column = dr.minimum(mi.UInt32(phi * self._columns_per_radian), self._last_column)
        return row, column

    def _radiance_at(self, direction, wavelengths, active):
        row, column = self._pixel(direction)
        base = (row * self._columns + column) * self._band_count
        value = mi.UnpolarizedSpectrum(0.0)
        for channel in range(4):
            position = (wavelengths[channel] - self._first_nm) / self._step_nm
            low = dr.minimum(mi.UInt32(dr.maximum(position, 0.0)), self._last_band_pair)
            high = dr.minimum(low + 1, self._band_count - 1)
            t = dr.clip(position - mi.Float(low), 0.0, 1.0)
            first = dr.gather(mi.Float, self._radiance, base + low, active)
            second = dr.gather(mi.Float, self._radiance, base + high, active)
            value[channel] = dr.select(active, first + t * (second - first), 0.0)
        return value

    def _pdf(self, direction):
        if not self._importance:
            return mi.Float(1 / (4 * dr.pi))
        row, column = self._pixel(direction)
        pmf = self._distribution.eval_pmf_normalized(row * self._columns + column)
        top = dr.cos(mi.Float(row) * self._row_radians)
        bottom = dr.cos(mi.Float(row + 1) * self._row_radians)
        return pmf / ((top - bottom) * self._column_radians)

    def eval(self, si, active=True):
        return self._radiance_at(-si.wi, si.wavelengths, active)

    def eval_direction(self, it, ds, active=True):
        return self._radiance_at(ds.d, it.wavelengths, active)

    def sample_direction(self, it, sample, active=True):
        if self._importance:
            index, reused = self._distribution.sample_reuse(sample.x, active)
            # lanes of other emitters read the opaque width as 0 in Mitsuba's calls: a divisor
            # of at least 1 keeps their (discarded) integer division from trapping
            columns = dr.maximum(self._columns, 1)
            row, column = index // columns, index % columns
            top = dr.cos(mi.Float(row) * self._row_radians)
            bottom = dr.cos(mi.Float(row + 1) * self._row_radians)
            cos_theta = top + reused * (bottom - top)
            phi = (mi.Float(column) + sample.y) * self._column_radians
            sin_theta = dr.safe_sqrt(1 - cos_theta * cos_theta)
            direction = mi.Vector3f(sin_theta * dr.cos(phi), sin_theta * dr.sin(phi), cos_theta)
        else:
            direction = mi.warp.square_to_uniform_sphere(sample)
        ds = dr.zeros(mi.DirectionSample3f)
        ds.d = direction
        ds.pdf = self._pdf(direction)
        ds.dist = self._radius
        ds.p = it.p + direction * self._radius
        ds.n = -direction
        ds.time = it.time
        ds.delta = False
        ds.emitter = mi.EmitterPtr(self)
        radiance = self._radiance_at(direction, it.wavelengths, active)
        return ds, dr.select(ds.pdf > 0, radiance / ds.pdf, 0.0)

    def pdf_direction(self, it, ds, active=True):
        return self._pdf(ds.d)

    def sample_wavelengths(self, si, sample, active=True):
        wavelengths = self._first_nm + self._span_nm * mi.sample_shifted(sample)
        return wavelengths, self._radiance_at(-si.wi, wavelengths, active) * self._span_nm

    def bbox(self):
        return mi.ScalarBoundingBox3f()

    def to_string(self):
        return f"SpectralEnvmapEmitter[{self._height} x {self._width} x {self._bands}]"


register_once("spectral_envmap", mi.register_emitter, lambda props: SpectralEnvmapEmitter(props))
