"""The simulated dome's spectrometer: the white standard's radiance under the LEDs lit.

Thesis 10.3 measures the LED spectrum with a spectrometer (an Ocean Optics USB4000) on the white
standard. The simulated one looks at the centre of the holder, where the white standard lies
during the calibration's white frames, and reads its radiance under the LEDs on at the time:
:math:`\\rho_w(\\lambda) / \\pi\\, I(\\lambda) \\sum_i (c / c_{max})\\, E_i`, with :math:`I` the
LEDs' radiant intensity, :math:`E_i` the irradiance per unit intensity of LED :math:`i` at the
centre (:func:`recon.calibration.dome_lighting.led_irradiance`) and :math:`c` the drive current.
Like a real one it integrates until its brightest pixel reaches :data:`PEAK_COUNTS`, so each
reading carries the shot noise of that many counts plus :data:`READ_NOISE_COUNTS`, and reports
counts scaled back to radiance units. Step ``k`` of a session with seed ``s`` draws its noise from
``numpy.random.default_rng([s, k, 7])``, so resumed and distributed captures read the same.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hwbridge.errors import InputError
from hwbridge.protocols import Reading, description, reading
from recon.calibration.dome_lighting import led_irradiance
from recon.spectra import WavelengthGrid
from twin.components.lamps import PhosphorWhiteLED
from twin.components.targets import zenith_white_reflectance

if TYPE_CHECKING:
    from twin.devices.sim_devices import VirtualRig

__all__ = [
    "PEAK_COUNTS",
    "READ_NOISE_COUNTS",
    "SPECTROMETER_GRID",
    "DomeSpectrometer",
    "SimDomeSpectrometer",
]

SPECTROMETER_GRID = WavelengthGrid.regular(380.0, 780.0, 1.0)
"""The spectrometer's wavelengths: 380-780 nm in 1 nm steps."""

PEAK_COUNTS = 40000.0
"""Counts of a reading's brightest wavelength (the spectrometer's integration time set so, about
60 % of a 16-bit range)."""

READ_NOISE_COUNTS = 8.0
"""Read noise per wavelength and reading, in counts."""

_NOISE_STREAM = 7  # the third seed word of the spectrometer's draws


@dataclass(frozen=True, eq=False)
class DomeSpectrometer:
    """The spectrometer's recipe (plain data: it pickles for the workers of a cluster).

    Attributes
    ----------
    radiance_per_irradiance
        ``(n,)`` the white standard's radiance per unit LED irradiance at full current,
        :math:`\\rho_w I / \\pi`, on :attr:`grid`.
    irradiance
        ``(n_leds,)`` irradiance per unit intensity of every LED at the holder's centre.
    full_scale_ma
        The current at which the LEDs emit :math:`I`.
    grid
        The spectrometer's wavelengths.
    """

    radiance_per_irradiance: np.ndarray
    irradiance: np.ndarray
    full_scale_ma: float
    grid: WavelengthGrid = SPECTROMETER_GRID

    @classmethod
    def of_dome(cls, led_positions_m: np.ndarray, full_scale_ma: float) -> DomeSpectrometer:
        """The spectrometer of a dome whose LEDs lie at ``led_positions_m`` ``(n_leds, 3)``
        (world frame, the holder's centre at the origin)."""
        grid = SPECTROMETER_GRID
        radiance = (
            zenith_white_reflectance(grid).values
            * PhosphorWhiteLED().intensity(grid).values
            / np.pi
        )
        irradiance = led_irradiance(np.zeros(3), np.asarray(led_positions_m, np.float64))
        return cls(radiance, np.atleast_1d(irradiance), float(full_scale_ma), grid)

    def on_rig(self, rig: VirtualRig) -> SimDomeSpectrometer:
        """The device over ``rig`` (a :class:`twin.devices.sim_devices.VirtualRig`)."""
        return SimDomeSpectrometer(rig, self)


class SimDomeSpectrometer:
    """The spectrometer as a device (:class:`hwbridge.protocols.LampMonitor`): ``trigger``
    takes a reading of the white standard under the LEDs on, ``read`` returns it."""

    def __init__(self, rig: VirtualRig, recipe: DomeSpectrometer, *, name: str = "spectrometer"):
        self.name, self._rig, self._recipe = name, rig, recipe
        self._last: np.ndarray | None = None

    @property
    def samples(self) -> int:
        return self._recipe.grid.size

    def _step_taken(self) -> int:
        """The plan step of the frame just taken (the session reads after each frame)."""
        taken = max(self._rig.frames_taken - 1, 0)
        steps = self._rig.steps
        return taken if steps is None else int(steps[min(taken, len(steps) - 1)])

    def trigger(self) -> None:
        self._rig.maybe_fail(f"{self.name}.trigger")
        recipe = self._recipe
        pattern = self._rig.led_pattern
        lit = 0.0 if pattern is None else float(np.asarray(pattern, bool) @ recipe.irradiance)
        signal = recipe.radiance_per_irradiance * lit * self._rig.led_current_ma
        signal = signal / recipe.full_scale_ma
        peak = float(signal.max())
        scale = PEAK_COUNTS / peak if peak > 0 else 1.0
        counts = signal * scale
        rng = np.random.default_rng([self._rig.seed, self._step_taken(), _NOISE_STREAM])
        noisy = rng.normal(counts, np.sqrt(counts + READ_NOISE_COUNTS**2))
        self._last = noisy / scale

    def read(self) -> Reading:
        if self._last is None:
            raise InputError(f"{self.name}: no spectrum yet; call trigger() first")
        return reading(f"{self.name}_radiance", self._last)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_radiance",
            source="simulated",
            dtype="array",
            shape=[self.samples],
            units="W m^-2 sr^-1 nm^-1",
        )
