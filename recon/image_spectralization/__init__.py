"""A user's RGB image and spot spectra spectralized (thesis chapter 6): the linear RGB image
(``rgb_image``), the spot spectra at pixel coordinates (``spots``), the camera's response by
name or from a CSV (``responses``), tables of spectra by wavelength (``wavelength_table``) and
the reconstruction with its cross-validated error per spot (``run``).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "responses": ["camera_response", "read_response_csv"],
        "wavelength_table": ["read_wavelength_table"],
        "rgb_image": ["LinearRGB", "read_linear_rgb"],
        "run": ["ImageSpectralization", "spectralize_image"],
        "spots": ["SpotSpectra", "read_spots_csv"],
    },
)
