"""Band schedules and spectral exposure plans of the LED dome's spectral camera (thesis 10.4)."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "dome_schedule": ["BandSchedule", "fewest_images", "schedule_bands", "spectral_exposures"],
    },
)
