"""Mitsuba rendering: the variant, spectra handed to Mitsuba, shapes, rendering a scene to an
image, lamp groups, rig scenes, the analytic flat-target scene and the noise-free truth of a
material.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submodules=["plugins"],
    submod_attrs={
        "bench_scene": ["render_chart_bench"],
        "flat_target": ["render_flat_target"],
        "light_groups": ["render_lit"],
        "render": ["render_scene"],
        "scene": ["PinholeCamera", "render_view"],
        "truth": ["texture_truth", "truth_btf"],
        "variant": ["activate"],
    },
)
