"""The virtual spectral gonioreflectometer (thesis 3.3, 4.1.1): renders and raw frames per
direction pair, the signals of its simulated camera, capture programs and capture time.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "capture": [
            "CAMERA_ID",
            "GonioPairs",
            "REDUCED_RINGS",
            "actual_poses",
            "gonio_pairs",
            "run_gonio_calibration",
            "run_gonio_measurement",
            "texture_corners_world",
        ],
        "capture_time": [
            "GonioEstimate",
            "band_exposures_s",
            "estimate_gonio",
            "move_seconds",
            "order_pairs",
        ],
        "render": [
            "gonio_camera",
            "gonio_lamp",
            "gonio_part_rates",
            "pose_matrix",
            "simulate_band_frames",
        ],
        "signals": ["RenderedGonioSignal", "WhiteReferenceSignal"],
        "sim_session": ["demo_plan", "run_demo_session"],
    },
)
