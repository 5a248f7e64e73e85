"""EMVA 1288 measurements of real cameras: the descriptor and its images, their analysis with
the ``emva1288`` package, what its estimators see in quantized frames, and the fit of the camera
model's parameters to it.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "analysis": ["EMVAAnalysis", "analyse_measurement"],
        "descriptor": ["EMVADescriptor", "EMVAStep", "read_descriptor", "write_descriptor"],
        "fit": ["FittedSensor", "fit_sensor"],
        "linear_model": ["knee_oecf", "predicted_saturation_e"],
        "quantization": ["QuantizedMoments", "quantized_moments", "unquantized_spread"],
    },
)
