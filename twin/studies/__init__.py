"""The thesis's studies on the twin (chapters 7, 9, 10), a camera characterized from real chart
photographs written out (``spectwin camchar``), the camera bench, the rig gallery,
``spectwin demo`` with its report, design sweeps (``spectwin sweep``) and a real bench's twin
against its capture (``spectwin twin-vs-real``).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "camchar": ["run_camchar"],
        "camchar_cameras": ["run_camchar_cameras"],
        "camchar_photos": ["write_characterization"],
        "camera_bench": ["run_camera_report"],
        "demo": ["run_demo"],
        "dome": ["run_dome_study"],
        "gallery": ["run_gallery"],
        "spectralization": ["run_study"],
        "sweep_file": ["check_points", "load_sweep"],
        "sweep_run": ["run_sweep"],
        "twin_vs_real": ["run_twin_vs_real"],
    },
)
