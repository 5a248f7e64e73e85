"""Calibration of the rigs from capture stores: the gonioreflectometer (thesis 3.3), its spectral
white factors and exposure plan, and the dome's RGB and spectral cameras (thesis 10.3).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture_io": ["select_frames"],
        "dome": ["calibrate_rgb_camera", "calibrate_spectral_camera"],
        "dome_capture": ["DomeCalibration", "calibrate_dome"],
        "gonio": ["GonioCalibration", "calibrate_gonio"],
        "spectral": ["plan_exposures", "reflectance", "white_factors"],
    },
)
