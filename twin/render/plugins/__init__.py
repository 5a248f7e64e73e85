"""spectwin's Python plugins for Mitsuba: the measured spectral BTF as a BSDF and the spectral
environment map emitter.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "btf_bsdf": [
            "BTFTable",
            "CompressedTable",
            "barycentric",
            "btf_bsdf",
            "compressed_product_table",
            "hemisphere_lookup",
            "interpolate_table",
            "product_table",
            "store_table",
            "written_table",
        ],
        "registry": ["PluginData", "register_once"],
        "spectral_envmap": ["SpectralMap", "register_map", "spectral_envmap"],
    },
)
