"""The chapter 7 experiments: sparse sampling protocols, synthetic images and the comparison of
spectralization with the usual recovery methods.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "sampling": [
            "add_rgb_noise",
            "exclude_region",
            "grid_layout",
            "known_spectra_from_mask",
            "push_broom_mask",
            "spot_mean_spectra",
            "whisk_broom_mask",
        ],
        "sparse": [
            "METHODS",
            "ProtocolResult",
            "SparseInput",
            "noise_sweep",
            "run_protocol",
            "spot_count_sweep",
        ],
        "synthetic_images": ["material_mosaic"],
    },
)
