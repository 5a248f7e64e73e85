"""Mitsuba rendering: the variant, spectra handed to Mitsuba, shapes, rendering a scene to an
image, lamp groups, rig scenes, the analytic flat-target scene and the noise-free truth of a
material.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submodules=["plugins"],
    submod_attrs={
        "flat_target": [
            "analytic_band_radiance",
            "flat_target_scene",
            "patch_means",
            "render_flat_target",
        ],
        "light_groups": ["LightGroup", "lamp_weighted_channels", "render_lit"],
        "render": ["render_scene"],
        "scene": ["PinholeCamera", "lamp_position", "render_view"],
        "shapes": ["mitsuba_shape", "part_bsdf"],
        "spectra": ["channel_name", "irregular_spectrum", "ldsampler", "rendered_spp", "specfilm"],
        "truth": ["band_passbands", "texture_truth", "truth_btf", "truth_camera_signal"],
        "variant": [
            "DEFAULT_VARIANT",
            "FALLBACK_VARIANT",
            "VariantReport",
            "activate",
            "choose_variant",
            "llvm_version",
        ],
    },
)
