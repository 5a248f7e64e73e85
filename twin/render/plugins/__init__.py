"""spectwin's Python plugins for Mitsuba: the measured spectral BTF as a BSDF and the spectral
environment map emitter.

Each plugin module activates the Mitsuba variant when imported and defines its plugin class at
module level (:mod:`twin.render.plugins.registry`). The functions that build a scene entry,
``btf_bsdf.btf_bsdf`` and ``spectral_envmap.spectral_envmap``, are imported from their modules:
the package re-exports no name that would hide a module.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "btf_bsdf": [
            "BTFTable",
            "CompressedTable",
            "SpectralBTF",
            "barycentric",
            "compressed_product_table",
            "hemisphere_lookup",
            "interpolate_table",
            "product_table",
            "store_table",
            "written_table",
        ],
        "registry": ["PluginData", "register_once"],
        "spectral_envmap": [
            "SpectralEnvmapEmitter",
            "SpectralMap",
            "register_map",
        ],
    },
)
