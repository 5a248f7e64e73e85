"""Registration of the sample holder's border in gonioreflectometer frames and the homography to
texture space (thesis 4.1.2).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "border": [
            "CornerDetection",
            "MarksNotFoundError",
            "detect_corners",
            "extract_texture",
            "local_pca_lines",
            "order_corners",
            "parse_manual_corners",
            "read_manual_corners",
            "register_frame",
        ],
        "corners": [
            "TEXTURE_CORNERS_UV",
            "corner_pieces",
            "fit_corner_model",
            "frame_intensity",
            "refine_corners",
            "texture_transform",
            "validate_corners",
            "validate_frame",
            "validate_marks",
        ],
    },
)
