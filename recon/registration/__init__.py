"""Registration of the sample holder's border in gonioreflectometer frames and the homography to
texture space (thesis 4.1.2).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "border": ["detect_corners", "extract_texture", "register_frame"],
        "corners": ["refine_corners", "texture_transform"],
        "sample_plane": ["sample_square_corners"],
    },
)
