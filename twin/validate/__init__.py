"""Validation of measured BTFs: evaluation against the twin's truth (at the measured pairs and at
held-out ones), the 45/0 spectrophotometer comparison, the environment map capture, the Figure
4.6 rendering and the smoke render.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "envmap_capture": ["capture_mirror_sphere"],
        "figure46": ["render_figure46"],
        "gonio_evaluation": ["evaluate_gonio"],
        "held_out": ["held_out_errors"],
        "render_back": ["validate_btf"],
        "smoke": ["run_smoke"],
        "spectrophotometer": ["compare_45_0"],
    },
)
