"""Validation of measured BTFs: evaluation against the twin's truth (at the measured pairs and at
held-out ones), the 45/0 spectrophotometer comparison, the environment map capture, the Figure
4.6 rendering, the validation against a user's photograph from files, the smoke render and the
preview of any BTF store.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "btf_preview": ["render_btf_preview"],
        "envmap_capture": ["capture_mirror_sphere"],
        "figure46": ["render_figure46"],
        "gonio_evaluation": ["evaluate_gonio"],
        "held_out": ["held_out_errors"],
        "photo_validation": ["read_photo_inputs", "validate_photo"],
        "preview_lighting": ["PRESETS", "environment_lighting"],
        "render_back": ["validate_btf"],
        "smoke": ["run_smoke"],
        "spectrophotometer": ["compare_45_0"],
    },
)
