"""Band schedules and spectral exposure plans of the LED dome's spectral camera (thesis 10.4)."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "dome_schedule": [
            "BandSchedule",
            "DEFAULT_NODE_LIMIT",
            "FILTER_SIZE_PER_SIGMA",
            "THESIS_RGB_EXPOSURES_S",
            "fewest_images",
            "filter_sizes",
            "gaussian_noise_factor",
            "schedule_bands",
            "spectral_exposures",
        ],
    },
)
