"""The virtual spectral gonioreflectometer (thesis 3.3, 4.1.1): renders and raw frames per
direction pair, the signals of its simulated camera, capture programs and capture time.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture": ["run_gonio_calibration", "run_gonio_measurement"],
        "capture_time": ["estimate_gonio"],
        "render": ["simulate_band_frames"],
        "sim_session": ["run_demo_session"],
    },
)
