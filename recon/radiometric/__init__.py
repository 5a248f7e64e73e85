"""Radiometric calibration entry points (dark frames, response curve, HDR merge) in one place.

The implementations live in :mod:`recon.radiometric.dark_frames`,
:mod:`recon.radiometric.response_curve` and
:mod:`recon.radiometric.hdr`; this module is the stable import path named in ARCHITECTURE.md
(``recon.radiometric.robertson(frames, exposures, **options) -> (inverse_response, radiance)``).
"""

from recon.radiometric.dark_frames import average_dark_frames, dark_frames_at, subtract_dark
from recon.radiometric.hdr import merge_hdr, predict_values, response_histogram
from recon.radiometric.response_curve import robertson, robertson_filtered

__all__ = [
    "average_dark_frames",
    "dark_frames_at",
    "merge_hdr",
    "predict_values",
    "response_histogram",
    "robertson",
    "robertson_filtered",
    "subtract_dark",
]
