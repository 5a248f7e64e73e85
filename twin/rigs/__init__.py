"""The rigs as declarative models, without a renderer: YAML schemas of cameras and rigs,
hemisphere samplings, gonioreflectometer kinematics and dome geometry.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "bench_config": ["load_bench"],
        "camera_config": ["load_camera_config"],
        "dome_geometry": ["dome_geometry"],
        "gonio_kinematics": ["solve_pairs"],
        "hemisphere": ["direction", "sattler_directions"],
        "rig_config": ["load_rig"],
    },
)
