"""The virtual LED dome (thesis chapter 10): renders and raw frames of its RGB and spectral
cameras, the spectral side's calibration and exposure plan, the chapter 10 study's analytic
captures, and the rendered capture programs that write capture stores (``programs``) with their
capture time (``capture_time``).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture": ["dome_cameras"],
        "capture_study": ["reconstruct_capture", "simulate_capture"],
        "capture_time": ["estimate_dome"],
        "programs": ["dome_calibration_program", "dome_run_program"],
        "render": ["dome_rates"],
        "setup": ["DomeSetup", "dome_setup"],
    },
)
