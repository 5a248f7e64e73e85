"""A user's RGB image and spot spectra spectralized (thesis chapter 6): the linear RGB image
(``rgb_image``), the spot spectra at pixel coordinates (``spots``), the camera's response by
name or from a CSV (``responses``), the camera term fitted to the spots (``camera_fit``), tables
of spectra by wavelength (``wavelength_table``),
the reconstruction with its cross-validated error per spot (``run``), the window a large image
is cross-validated in (``window``) and the blend with Murakami's kriged estimate weighted by
the same folds (``kriging_blend``).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "camera_fit": ["CameraTerm", "camera_term"],
        "kriging_blend": ["KrigingWeight", "blend_with_kriging", "choose_kriging_weight"],
        "responses": ["camera_response", "read_response_csv"],
        "rgb_image": ["LinearRGB", "read_linear_rgb", "write_rgb_exr"],
        "wavelength_table": ["read_wavelength_table"],
        "run": ["ImageSpectralization", "spectralize_image"],
        "spots": ["SpotSpectra", "read_spot_mask", "read_spots_csv"],
        "window": ["Window", "cross_validation_window"],
    },
)
