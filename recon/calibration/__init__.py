"""Calibration of the rigs from capture stores: the gonioreflectometer (thesis 3.3), its spectral
white factors and exposure plan, and the dome's RGB and spectral cameras (thesis 10.3).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture_io": ["FrameSelection", "select_frames"],
        "dome": [
            "DARK_VALUE_OFFSET",
            "RgbCameraCalibration",
            "SpectralCameraCalibration",
            "calibrate_rgb_camera",
            "calibrate_spectral_camera",
            "curve_linearity",
            "texel_mean",
        ],
        "gonio": [
            "DarkModel",
            "GonioCalibration",
            "calibrate_gonio",
            "dark_model",
            "extend_curve",
            "store_white_factors",
            "white_reflectance",
        ],
        "spectral": [
            "HMI_FLICKER_PERIOD_S",
            "drift_factors",
            "plan_exposures",
            "reflectance",
            "run_white_factors",
            "white_factors",
        ],
    },
)
