"""Camera characterization from real photographs of a chart (thesis chapter 9): the photographs
read as linear signal (camera raw, 16-bit TIFF and PNG), the charts and lights by name or from
CSV files, the patches sampled between the chart's corners (given, or found by
colour-checker-detection), exposures merged, and the response estimated by
``recon.camera_char``.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "characterize": [
            "ChartPhotograph",
            "PhotoCharacterization",
            "characterize_photographs",
            "estimation_grid",
        ],
        "charts": ["CHARTS", "Chart", "chart_from_csv", "colorchecker_reflectances", "named_chart"],
        "detect": ["detect_colorchecker"],
        "images": ["ENCODINGS", "LinearPhoto", "read_photo"],
        "lights": ["light_names", "light_spectrum"],
        "patches": ["merge_exposures", "sample_patches"],
        "spectra_files": ["read_spectra_file"],
        "truth": [
            "MeasuredResponse",
            "TruthErrors",
            "check_truth",
            "read_truth",
            "truth_errors",
            "truth_on_grid",
        ],
    },
)
