"""Hand spectwin spectra to Mitsuba: irregular spectra, the ``specfilm`` band film and its
low-discrepancy sampler.

``SampledSpectra`` become Mitsuba ``irregular`` spectra with explicit values (never a bare float,
which Mitsuba would turn into a D65-shaped emitter: ARCHITECTURE.md, "Mitsuba notes").
``specfilm`` records, per channel, the integral of radiance times the channel's response curve
(not normalized), i.e. the band integral of thesis Eq. 6.1 / 10.9.
"""

from __future__ import annotations

import re

from recon.errors import InputError
from recon.spectra import SampledSpectra

__all__ = ["channel_name", "irregular_spectrum", "ldsampler", "rendered_spp", "specfilm"]


def irregular_spectrum(spectrum: SampledSpectra) -> dict[str, str]:
    """A Mitsuba ``irregular`` spectrum dict for one spectrum (1-D values)."""
    if spectrum.values.ndim != 1:
        raise InputError(
            f"irregular_spectrum: expected one spectrum (1-D values), got shape "
            f"{spectrum.values.shape}"
        )
    return {
        "type": "irregular",
        "wavelengths": ", ".join(f"{w:.10g}" for w in spectrum.wavelengths_nm),
        "values": ", ".join(f"{v:.10g}" for v in spectrum.values),
    }


def channel_name(name: str) -> str:
    """A film channel name Mitsuba accepts: letters, digits and underscores."""
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


def rendered_spp(spp: int) -> int:
    """The sample count Mitsuba's ``ldsampler`` renders for a request of ``spp``: the next power
    of 4 (its low-discrepancy sequence needs a square power of two; 32 becomes 64)."""
    if int(spp) < 1:
        raise InputError(f"spp: expected at least 1 sample per pixel, got {spp}")
    count = 1
    while count < int(spp):
        count *= 4
    return max(count, 4)


def ldsampler(spp: int) -> dict[str, object]:
    """A Mitsuba ``ldsampler`` dict for at least ``spp`` samples per pixel (:func:`rendered_spp`),
    given as a count Mitsuba takes without rounding (and without a warning)."""
    return {"type": "ldsampler", "sample_count": rendered_spp(spp)}


def specfilm(responses: SampledSpectra, width: int, height: int) -> dict[str, object]:
    """A ``specfilm`` dict with one channel per row of ``responses`` (values ``(n, K)``).

    Channels keep the order of the rows; they are named after ``responses.names`` when given.
    """
    if responses.values.ndim != 2:
        raise InputError(
            f"specfilm: expected responses of shape (n_channels, K), got {responses.values.shape}"
        )
    if width < 1 or height < 1:
        raise InputError(f"specfilm: expected a positive size, got {width}x{height}")
    responses.require_non_negative("specfilm responses")
    names = responses.names or tuple(f"band_{i:03d}" for i in range(responses.values.shape[0]))
    film: dict[str, object] = {
        "type": "specfilm",
        "width": int(width),
        "height": int(height),
        "rfilter": {"type": "box"},
    }
    for index, name in enumerate(names):
        # Mitsuba sorts film channels by property name: prefix the index to keep row order.
        film[f"c{index:03d}_{channel_name(name)}"] = irregular_spectrum(
            SampledSpectra(responses.grid, responses.values[index])
        )
    return film
