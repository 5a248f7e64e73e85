"""Hardware-independent science of spectwin.

Spectra and wavelength grids, spectral image I/O, and (in later modules) calibration,
spectralization, metrics and BTF storage. Never imports ``twin``, ``mitsuba`` or ``drjit``:
real captures must be processable on a machine without a renderer.
"""
