"""The camera sensor model (EMVA 1288 physics, radiance to raw frames) and the white reference
signal that sets band exposure times (thesis Eq. 3.3-3.4).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "band_weights": ["instrument_passbands"],
        "model": ["Sensor"],
        "reduced_copy": ["reduce_raw_frame"],
        "white_reference": ["equalized_exposures_s"],
    },
)
