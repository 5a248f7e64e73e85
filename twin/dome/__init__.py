"""The virtual LED dome (thesis chapter 10): renders and raw frames of its RGB and spectral
cameras, the spectral side's calibration and exposure plan, and virtual captures.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture": ["DomeCameras", "THESIS_BANDS_NM", "dome_cameras", "pixels_per_texel"],
        "capture_study": [
            "DomeCapture",
            "MATERIAL_TEXEL_REFLECTANCE",
            "ReconstructionErrors",
            "dome_light_directions",
            "reconstruct_capture",
            "simulate_capture",
            "sphere_lit_spectra",
        ],
        "render": ["dome_camera", "dome_rates", "stage_matrix"],
        "setup": [
            "BAND_GRID",
            "CALIBRATION_LIGHT",
            "DARK_FRAMES_PER_TIME",
            "DomeSetup",
            "SPECTRAL_VIEW",
            "THESIS_LONGEST_BAND_S",
            "dome_setup",
        ],
    },
)
