"""The chapter 7 experiments: sparse sampling protocols, synthetic images and the comparison of
spectralization with the usual recovery methods.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "sampling": ["push_broom_mask", "whisk_broom_mask"],
        "sparse": ["noise_sweep", "run_protocol", "spot_count_sweep"],
        "synthetic_images": ["material_mosaic"],
    },
)
