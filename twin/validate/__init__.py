"""Validation of measured BTFs: evaluation against the twin's truth, the 45/0 spectrophotometer
comparison, the environment map capture, the Figure 4.6 rendering and the smoke render.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "envmap_capture": ["capture_mirror_sphere", "unwrap_mirror_sphere"],
        "figure46": [
            "Figure46",
            "field_interiors",
            "render_figure46",
            "room_entries",
            "room_lights",
            "write_figure46",
        ],
        "gonio_evaluation": [
            "FieldMasks",
            "GonioEvaluation",
            "evaluate_gonio",
            "field_masks",
            "write_gonio_figure",
        ],
        "render_back": ["MIN_PIXELS", "validate_btf"],
        "smoke": ["SMOKE_TOLERANCE", "run_smoke"],
        "spectrophotometer": ["FortyFiveZero", "compare_45_0", "field_spots", "write_45_0_figure"],
    },
)
