"""The virtual LED dome (thesis chapter 10): renders and raw frames of its RGB and spectral
cameras, the spectral side's calibration and exposure plan, and virtual captures.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture": ["dome_cameras"],
        "capture_study": ["reconstruct_capture", "simulate_capture"],
        "render": ["dome_rates"],
        "setup": ["DomeSetup", "dome_setup"],
    },
)
