"""The rigs as declarative models, without a renderer: YAML schemas of cameras and rigs,
hemisphere samplings, gonioreflectometer kinematics and dome geometry.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "camera_config": ["CAMERA_DIR", "CameraConfig", "available_cameras", "load_camera_config"],
        "dome_geometry": [
            "DomeGeometry",
            "dome_capture_seconds",
            "dome_geometry",
            "to_sample_frame",
        ],
        "gonio_kinematics": [
            "GonioPose",
            "GonioSolution",
            "forward_directions",
            "perturbed_pose",
            "solve_pairs",
        ],
        "hemisphere": [
            "SATTLER_RINGS",
            "angle_between_deg",
            "direction",
            "sattler_directions",
            "spherical_deg",
        ],
        "rig_config": ["DomeConfig", "GonioConfig", "RIG_DIR", "available_rigs", "load_rig"],
        "yaml_config": [
            "NonNegative",
            "Positive",
            "StrictModel",
            "read_yaml_mapping",
            "resolve_scene_file",
            "scene_folder",
            "scene_names",
            "validate_document",
        ],
    },
)
