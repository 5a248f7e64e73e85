"""Camera sensor model: radiance on the sensor to raw frames, with EMVA 1288 physics.

Mitsuba gives radiance; real cameras give raw digital numbers. Between the two:

1. Optics and photon conversion. A lens of f-number :math:`N` and transmission :math:`\\tau`
   turns scene radiance :math:`L` into sensor irradiance :math:`E = \\pi \\tau L / (4 N^2)`
   (distant object, on axis). A pixel of area :math:`A` collecting for :math:`t` seconds gets
   :math:`\\mu_e = \\frac{\\pi \\tau A}{4 N^2} \\int H(\\lambda)\\, \\eta(\\lambda) T(\\lambda)
   \\frac{\\lambda}{hc} d\\lambda` photo-electrons, with :math:`H = \\int_t L\\, dt` the radiant
   exposure, :math:`\\eta` the quantum efficiency and :math:`T` a filter (e.g. an LCTF band).
   Thesis Eq. 10.9 is the special case of this integral for the RGB cameras.
2. Fixed patterns (drawn once per camera serial): photo-response non-uniformity (PRNU),
   dark-signal non-uniformity (DSNU) of the dark current with hot pixels, dark charge picked up
   along the CCD shift direction (thesis Fig. 10.2d), and per-pixel offsets (the part of the
   DSNU that does not grow with exposure time).
3. Temporal noise: Poisson shot noise of photo and dark electrons, with the dark current
   following the doubling-temperature law (so the cooled K4 has almost none); full-well clip;
   read noise (3 DN for the K4, thesis 10.3). From :data:`GAUSSIAN_SHOT_E` mean electrons on,
   the Poisson count is drawn as its Cornish-Fisher normal approximation, rounded to whole
   electrons (:func:`shot_electrons`: the same mean, variance and skewness, a fifth of the
   cost).
4. Conversion: system gain K, a monotone OECF (thesis 3.3: :math:`p = f(tI) + d`, Eq. 3.1;
   :mod:`recon.emva.linear_model`), ADC offset, quantization to the bit depth and clamping to
   :math:`[0, 2^n - 1]`.
5. For colour sensors, a Bayer mosaic (RGGB or GBRG) picks one channel per pixel.

Every stochastic call takes a ``numpy.random.Generator``: the same seed gives the same frame.

References
----------
- EMVA Standard 1288, Release 4.0 Linear (2021), European Machine Vision Association:
  :math:`\\mu_y = \\mu_{y.dark} + K \\eta \\mu_p`,
  :math:`\\sigma_y^2 = K^2 \\sigma_d^2 + \\sigma_q^2 + K (\\mu_y - \\mu_{y.dark})`.
- Janesick, J. R. (2007). Photon Transfer. SPIE Press. doi:10.1117/3.725073 (dark current
  doubling temperature, fixed pattern noise).
- The thesis: Eq. 3.1-3.2 (imaging model), section 3.2.2 (CoolSNAP K4), section 10.3 and
  Fig. 10.2d (dark frames, read noise of 3 DN), Eq. 10.9 (RGB camera response).
"""

from __future__ import annotations

import math
import zlib
from concurrent.futures import ThreadPoolExecutor
from functools import cached_property

import numpy as np
from scipy import constants

from recon.emva.linear_model import knee_oecf, predicted_saturation_e
from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid, band_integrals
from twin.rigs.camera_config import CameraConfig, load_camera_config

__all__ = ["GAUSSIAN_SHOT_E", "Sensor", "bayer_channel_index", "mosaic_channels", "shot_electrons"]

GAUSSIAN_SHOT_E = 10.0
"""Mean electrons from which the shot noise is drawn as a normal approximation of the Poisson
count (:func:`shot_electrons`, within 0.25 % of it in total variation); below it, as Poisson
counts."""

_ROW_BLOCKS = 2  # fixed, so the same seed gives the same frame whatever the thread count
_THREADS = 2  # numpy's generators release the GIL: the row blocks are drawn on two threads
_POOL_MIN_PIXELS = 192 * 192  # smaller frames are drawn on the calling thread (same blocks, same
# generators, so the same frame): handing two blocks to the threads and waiting for them cost
# more than drawing a 128 x 128 frame's noise
_pool: ThreadPoolExecutor | None = None


def _row_pool() -> ThreadPoolExecutor:
    """The threads that draw row blocks, started once per process (starting two threads for
    every frame cost as much as drawing a 256 x 256 frame's noise)."""
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=_THREADS, thread_name_prefix="sensor")
    return _pool


def bayer_channel_index(height: int, width: int, pattern: str = "RGGB") -> np.ndarray:
    """Channel index (0 = R, 1 = G, 2 = B) of every pixel of a Bayer mosaic, ``(H, W)``.

    ``pattern`` names the colours of the 2 x 2 tile read row by row (``"RGGB"``, ``"GBRG"``, ...).

    Examples
    --------
    >>> bayer_channel_index(2, 4, "GBRG").tolist()
    [[1, 2, 1, 2], [0, 1, 0, 1]]
    """
    if sorted(pattern) != ["B", "G", "G", "R"]:
        raise InputError(f"pattern: expected a Bayer tile such as RGGB, got {pattern!r}")
    tile = np.array(["RGB".index(letter) for letter in pattern]).reshape(2, 2)
    return np.tile(tile, (height // 2 + 1, width // 2 + 1))[:height, :width]


def shot_electrons(mean_electrons: np.ndarray, generator: np.random.Generator) -> np.ndarray:
    """Electrons counted in pixels of ``mean_electrons`` (float32): Poisson counts of that mean.

    Below :data:`GAUSSIAN_SHOT_E` they are Poisson draws. From there on a Poisson count of mean
    :math:`\\lambda` is drawn as its first-order Cornish-Fisher expansion,
    :math:`\\lambda + s z + (z^2 - 1) / 6` with :math:`z` standard normal, rounded to a whole
    number: its mean is :math:`\\lambda`, with :math:`s^2 = \\lambda - 5/36` its variance
    is :math:`\\lambda` (the expansion's term adds 1/18, the rounding 1/12) and its third
    cumulant :math:`\\lambda` (Poisson's) to 0.1; its fourth cumulant is
    :math:`4 \\lambda / 3` instead of :math:`\\lambda`. Its distribution differs from
    Poisson's by a total variation distance of 0.22 % at the threshold (:math:`\\lambda = 10`),
    0.07 % at 30 and 0.02 % at 100 (a plain normal approximation, rounded: 4 %, 2.3 %, 1.3 %),
    far below what a frame's statistics resolve behind the read noise. A normal number costs a
    fifth of a Poisson count (12 against 40 to 75 ns here). Every pixel's normal number is drawn
    first, then the Poisson counts of the pixels below the threshold, in row-major order: the
    same generator state gives the same counts.

    References
    ----------
    - Cornish, E. A., Fisher, R. A. (1938). Moments and cumulants in the specification of
      distributions. Revue de l'Institut International de Statistique 5(4), 307-320.
    """
    normal = generator.standard_normal(mean_electrons.shape, np.float32)
    electrons = np.maximum(mean_electrons - np.float32(5 / 36), 0, dtype=np.float32)
    np.sqrt(electrons, out=electrons)
    electrons *= normal
    electrons += mean_electrons
    np.square(normal, out=normal)
    normal -= np.float32(1)
    normal *= np.float32(1 / 6)
    electrons += normal
    np.rint(electrons, out=electrons)
    low = mean_electrons < GAUSSIAN_SHOT_E
    if low.any():
        electrons[low] = generator.poisson(mean_electrons[low])
    return np.maximum(electrons, 0, out=electrons)


def mosaic_channels(image: np.ndarray, channel_index: np.ndarray) -> np.ndarray:
    """``(H, W)``: each pixel of an ``(H, W, 3)`` image in its own channel of ``channel_index``
    (:func:`bayer_channel_index`), as a Bayer sensor records it."""
    return np.take_along_axis(image, channel_index[..., None], axis=-1)[..., 0]


class Sensor:
    """A camera's sensor, optionally read out over a region of interest.

    Parameters
    ----------
    config
        The camera definition, or the name of a file in ``scenes/cameras``.
    roi
        ``(height, width)`` of a window at the sensor's top-left corner (as cameras read out a
        region of interest); the full sensor by default. Fixed patterns are those of the full
        sensor, cropped.
    """

    def __init__(self, config: CameraConfig | str, *, roi: tuple[int, int] | None = None):
        self.config = load_camera_config(config) if isinstance(config, str) else config
        height, width = roi or (self.config.height, self.config.width)
        if not (0 < height <= self.config.height and 0 < width <= self.config.width):
            raise InputError(
                f"roi: expected 1..{self.config.height} rows and 1..{self.config.width} columns, "
                f"got {height}x{width}"
            )
        self.height, self.width = int(height), int(width)

    # -- derived constants -------------------------------------------------------------------

    @property
    def is_colour(self) -> bool:
        return self.config.mosaic != "none"

    @property
    def channel_count(self) -> int:
        return 3 if self.is_colour else 1

    @property
    def max_dn(self) -> int:
        return 2**self.config.bit_depth - 1

    @property
    def pixel_area_m2(self) -> float:
        return (self.config.pixel_pitch_um * 1e-6) ** 2

    @property
    def etendue_m2_sr(self) -> float:
        """:math:`\\pi \\tau A / (4 N^2)`: radiance (W m^-2 sr^-1) to power on a pixel (W)."""
        optics = self.config.optics
        return math.pi * optics.transmission * self.pixel_area_m2 / (4 * optics.f_number**2)

    @property
    def dark_current_e_per_s(self) -> float:
        """Mean dark current at the sensor temperature: :math:`D_{ref} 2^{(T - T_{ref})/T_d}`."""
        dark = self.config.dark_current
        doublings = (self.config.sensor_temperature_c - dark.reference_temperature_c) / (
            dark.doubling_temperature_c
        )
        return dark.e_per_s_at_reference * 2.0**doublings

    @property
    def saturation_capacity_e(self) -> float:
        """Electrons at which the output clips: full well, or the ADC top with a linear OECF."""
        adc_top_e = (self.max_dn - self.config.adc_offset_dn) / self.config.system_gain_dn_per_e
        return min(self.config.full_well_e, adc_top_e)

    def emva_saturation_capacity_e(self) -> float:
        """Saturation capacity by the EMVA 1288 definition, predicted from this model.

        EMVA 1288 places saturation where the temporal variance of the output peaks, which for a
        clipped signal lies a few noise widths below the hard clip (:attr:`saturation_capacity_e`):
        :func:`recon.emva.linear_model.predicted_saturation_e`. Only defined for a linear OECF
        (EMVA 1288 Linear).
        """
        if self.config.oecf.model != "linear":
            raise InputError("emva_saturation_capacity_e: EMVA 1288 Linear needs a linear OECF")
        config = self.config
        return predicted_saturation_e(
            config.full_well_e,
            gain_dn_per_e=config.system_gain_dn_per_e,
            read_noise_dn=config.read_noise_dn,
            prnu=config.fixed_pattern.prnu_sigma,
            adc_top_dn=self.max_dn - config.adc_offset_dn,
        )

    # -- spectral response -------------------------------------------------------------------

    def quantum_efficiency(self, grid: WavelengthGrid) -> SampledSpectra:
        """:math:`\\eta(\\lambda)` per channel, values ``(1, K)`` or ``(3, K)`` (R, G, B)."""
        return self.config.quantum_efficiency.curve(grid)

    def electron_responses(
        self, grid: WavelengthGrid, filter_transmission: SampledSpectra | None = None
    ) -> SampledSpectra:
        """Electrons per unit spectral radiant exposure, per channel and filter band.

        Values ``(n, K)`` in e- per (J m^-2 sr^-1 nm^-1) per nm: the integrand
        :math:`\\frac{\\pi \\tau A}{4N^2} \\eta(\\lambda) T(\\lambda) \\lambda / (hc)`. With a
        filter of ``n_bands`` rows (a monochrome camera behind an LCTF) there is one row per band;
        a colour camera gives R, G, B rows (times the filter, which then must be a single row).
        """
        qe = self.quantum_efficiency(grid)
        photons_per_joule = grid.wavelengths_nm * 1e-9 / (constants.h * constants.c)
        per_channel = qe.values * photons_per_joule * self.etendue_m2_sr
        if filter_transmission is None:
            return SampledSpectra(grid, per_channel, qe.names)
        filter_transmission.require_non_negative("filter_transmission")
        if filter_transmission.grid != grid:
            raise InputError(
                f"filter_transmission: expected the grid {grid.describe()}, got "
                f"{filter_transmission.grid.describe()}"
            )
        rows = np.atleast_2d(filter_transmission.values)
        if self.is_colour and rows.shape[0] != 1:
            raise InputError(
                f"filter_transmission: a colour camera takes one filter, got {rows.shape[0]} bands"
            )
        names = filter_transmission.names if not self.is_colour else qe.names
        return SampledSpectra(grid, rows * per_channel, names)

    def mean_electrons(
        self,
        radiant_exposure: SampledSpectra,
        filter_transmission: SampledSpectra | None = None,
    ) -> np.ndarray:
        """Mean photo-electrons ``(..., n)`` from spectral radiant exposure ``(..., K)``.

        ``radiant_exposure`` is :math:`H(\\lambda) = \\int_t L(\\lambda, t) dt` in
        J m^-2 sr^-1 nm^-1 on a grid that resolves the filter and lamp features.
        """
        radiant_exposure.require_non_negative("radiant_exposure")
        responses = self.electron_responses(radiant_exposure.grid, filter_transmission)
        return band_integrals(radiant_exposure, responses)

    def electrons_from_monochromatic_irradiance(
        self, irradiance_w_m2: np.ndarray, wavelength_nm: float, exposure_s: float
    ) -> np.ndarray:
        """Mean photo-electrons under monochromatic light on the sensor plane (EMVA 1288 set-up).

        :math:`\\mu_e = \\eta(\\lambda) \\mu_p`, :math:`\\mu_p = E A t \\lambda / (hc)`. Returns
        ``(H, W)`` for a monochrome sensor and ``(H, W, 3)`` for a colour one.
        """
        self.check_exposure(exposure_s)
        irradiance = self._check_image(irradiance_w_m2, "irradiance_w_m2", channels=None)
        photons = (
            irradiance
            * self.pixel_area_m2
            * exposure_s
            * wavelength_nm
            * 1e-9
            / (constants.h * constants.c)
        )
        eta = self.quantum_efficiency(WavelengthGrid(np.array([wavelength_nm, wavelength_nm + 1])))
        eta_at = eta.values[:, 0]
        return photons * eta_at[0] if not self.is_colour else photons[..., None] * eta_at

    # -- fixed patterns ----------------------------------------------------------------------

    def _pattern_generator(self, pattern: int) -> np.random.Generator:
        """The generator of fixed pattern ``pattern`` (0 PRNU, 1 DSNU, 2 hot pixels, 3 offsets,
        4 defect pixels) of the window (the sensor's top-left ``height x width`` pixels).

        Each pattern is drawn from its own generator, seeded by the camera serial: the same
        serial always has the same patterns, as a real camera does. A generator fills the
        window's rows at the sensor's full width, row by row, so a pixel's values do not depend
        on the window, and a small window of a large sensor costs a small draw (the whole
        2448 x 2048 sensor's patterns took 0.5 s for every camera made). A camera without
        offsets or defects has the same other patterns as with them. Each pattern is drawn when
        first used (the ``cached_property`` below): the dark signal alone needs neither the PRNU
        nor the offsets.
        """
        return np.random.default_rng(self._pattern_seeds[pattern])

    @cached_property
    def _pattern_seeds(self) -> list[np.random.SeedSequence]:
        """The seeds of the five patterns' generators, spawned from the camera serial."""
        return np.random.SeedSequence(zlib.crc32(self.config.serial.encode())).spawn(5)

    @property
    def _pattern_rows(self) -> tuple[int, int]:
        """The shape a pattern is drawn in: the window's rows at the sensor's full width."""
        return self.height, self.config.width

    @cached_property
    def _photo_response(self) -> np.ndarray:
        prnu = self.config.fixed_pattern.prnu_sigma
        draw = self._pattern_generator(0).standard_normal(self._pattern_rows, np.float32)
        return np.clip(1 + prnu * draw[:, : self.width], 0, None)

    @cached_property
    def _dark_factor(self) -> np.ndarray:
        pattern = self.config.fixed_pattern
        # Log-normal with unit mean: the mean dark current stays the configured one.
        sigma = pattern.dsnu_sigma
        draw = self._pattern_generator(1).standard_normal(self._pattern_rows, np.float32)
        dark_factor = np.exp(sigma * draw - sigma**2 / 2)
        hot = self._pattern_generator(2).random(self._pattern_rows, np.float32)
        dark_factor[hot < pattern.hot_pixel_fraction] *= pattern.hot_pixel_factor
        return dark_factor[:, : self.width].astype(np.float32)

    @cached_property
    def _transfer_e(self) -> np.ndarray:
        row_index = np.arange(self.height, dtype=np.float32)[:, None]
        return (
            self.config.fixed_pattern.transfer_dark_e * row_index / max(self.config.height - 1, 1)
        )

    @cached_property
    def _offsets_and_defects(self) -> tuple[np.ndarray, np.ndarray]:
        pattern = self.config.fixed_pattern
        rows = self._pattern_rows
        if pattern.offset_sigma_dn > 0:
            offset = pattern.offset_sigma_dn * self._pattern_generator(3).standard_normal(
                rows, np.float32
            )
        else:
            offset = np.zeros((self.height, 1), np.float32)  # broadcasts over columns
        defects = np.zeros((self.height, 1), bool)  # broadcasts over columns
        if pattern.defect_pixel_fraction > 0:
            draw = self._pattern_generator(4).random(rows, np.float32)
            defects = draw < pattern.defect_pixel_fraction
            offset = np.broadcast_to(offset, rows).copy()
            offset[defects] += np.float32(pattern.defect_offset_dn)
        columns = slice(0, self.width)
        return offset[:, columns] + np.float32(self.config.adc_offset_dn), defects[:, columns]

    @cached_property
    def _mosaic_index(self) -> np.ndarray:
        """``(H, W)``: the flat index into an ``(H, W, 3)`` image of each pixel's own channel
        of the Bayer mosaic (:func:`mosaic_channels`)."""
        channel = bayer_channel_index(self.height, self.width, self.config.mosaic)
        pixels = np.arange(self.height * self.width, dtype=np.intp).reshape(self.height, -1)
        return pixels * 3 + channel

    def defect_pixels(self) -> np.ndarray:
        """``(H, W)`` bool: the defect pixels (``defect_pixel_fraction``), whose offset is
        ``defect_offset_dn`` higher at every exposure."""
        return np.broadcast_to(self._offsets_and_defects[1], (self.height, self.width))

    def mean_dark_electrons(self, exposure_s: float) -> np.ndarray:
        """Expected dark electrons per pixel, ``(H, W)``: dark current x time x DSNU + transfer."""
        self.check_exposure(exposure_s)
        return self.dark_current_e_per_s * exposure_s * self._dark_factor + self._transfer_e

    # -- capture -----------------------------------------------------------------------------

    def capture(
        self, photo_electrons: np.ndarray, exposure_s: float, rng: np.random.Generator
    ) -> np.ndarray:
        """One raw frame (uint16, ``(H, W)``; a Bayer mosaic for colour sensors).

        Parameters
        ----------
        photo_electrons
            Mean photo-electrons per pixel before PRNU: ``(H, W)`` for a monochrome sensor,
            ``(H, W, 3)`` for a colour one (R, G, B at every pixel; the mosaic picks one).
        exposure_s
            Exposure time, within the camera's ``exposure_range_s``; it sets the dark signal.
        rng
            Source of the temporal noise.
        """
        if not isinstance(rng, np.random.Generator):
            raise InputError(f"rng: expected a numpy.random.Generator, got {type(rng)}")
        electrons = self._check_image(
            photo_electrons, "photo_electrons", channels=3 if self.is_colour else None
        )
        if self.is_colour:  # each pixel's own channel (mosaic_channels), by a cached index
            electrons = np.take(electrons.reshape(-1), self._mosaic_index)
        mean = np.multiply(electrons, self._photo_response, dtype=np.float32)
        mean += self.mean_dark_electrons(exposure_s)
        blocks = np.array_split(np.arange(self.height), _ROW_BLOCKS)
        generators = rng.spawn(_ROW_BLOCKS)
        frame = np.empty((self.height, self.width), dtype=np.uint16)

        def convert(block: int) -> None:
            rows = slice(blocks[block][0], blocks[block][-1] + 1) if blocks[block].size else None
            if rows is not None:
                offset_dn = self._offsets_and_defects[0][rows]
                frame[rows] = self._digitize(mean[rows], offset_dn, generators[block])

        if self.height * self.width < _POOL_MIN_PIXELS:
            for block in range(_ROW_BLOCKS):
                convert(block)
        else:
            list(_row_pool().map(convert, range(_ROW_BLOCKS)))
        return frame

    def dark_frame(self, exposure_s: float, rng: np.random.Generator) -> np.ndarray:
        """A raw frame with the shutter closed."""
        shape = (self.height, self.width, 3) if self.is_colour else (self.height, self.width)
        return self.capture(np.zeros(shape, np.float32), exposure_s, rng)

    def oecf(self, linear_dn: np.ndarray) -> np.ndarray:
        """Opto-electronic conversion of the linear signal above offset, in DN (Eq. 3.1's f)."""
        if self.config.oecf.model == "linear":
            return linear_dn
        top = self.max_dn - self.config.adc_offset_dn
        return knee_oecf(linear_dn, top, self.config.oecf.strength)

    def _digitize(
        self, mean_electrons: np.ndarray, offset_dn: np.ndarray, generator: np.random.Generator
    ) -> np.ndarray:
        config = self.config
        signal_dn = shot_electrons(mean_electrons, generator)
        np.minimum(signal_dn, config.full_well_e, out=signal_dn)
        signal_dn *= config.system_gain_dn_per_e
        read_dn = generator.standard_normal(signal_dn.shape, np.float32)
        read_dn *= config.read_noise_dn
        signal_dn += read_dn
        digital = self.oecf(signal_dn)
        digital += offset_dn
        np.rint(digital, out=digital)
        return np.clip(digital, 0, self.max_dn, out=digital).astype(np.uint16)

    # -- validation --------------------------------------------------------------------------

    def check_exposure(self, exposure_s: float) -> None:
        """Raise :class:`InputError` unless ``exposure_s`` is a positive exposure time within the
        camera's ``exposure_range_s``."""
        low, high = self.config.exposure_range_s
        if not np.isfinite(exposure_s) or exposure_s <= 0:
            raise InputError(f"exposure_s: expected a positive exposure time, got {exposure_s}")
        if not low <= exposure_s <= high:
            raise InputError(
                f"exposure_s: {exposure_s} s is outside the {self.config.name}'s range "
                f"[{low}, {high}] s"
            )

    def _check_image(self, image: np.ndarray, what: str, channels: int | None) -> np.ndarray:
        image = np.asarray(image)
        expected = (self.height, self.width) + ((channels,) if channels else ())
        if image.shape[:2] != expected[:2] or (channels and image.shape != expected):
            raise InputError(
                f"{what}: expected shape {expected} for this sensor's readout, got {image.shape}"
            )
        if not np.all(np.isfinite(image)):
            raise InputError(f"{what}: expected finite values, found NaN or infinity")
        if np.any(image < 0):
            raise InputError(f"{what}: expected non-negative values")
        return image
