"""Camera spectral responses by Jiang et al. (2013): a basis learned from measured cameras.

Each channel's response is a combination of the first principal components (about the origin)
of the peak-normalized responses of measured cameras, fitted to the chart's device RGB by
linear least squares. No shading, specularity or smoothness terms: the peer that the extended
estimator (``recon.camera_char``, thesis Eq. 9.6-9.14) is compared with on the same photographs.
The computation is colour-science's: ``colour.recovery.PCA_Jiang2013`` learns the basis and
``colour.recovery.RGB_to_msds_camera_sensitivities_Jiang2013`` fits it.

References
----------
- Jiang, J., Liu, D., Gu, J., & Süsstrunk, S. (2013). What is the space of spectral sensitivity
  functions for digital color cameras? IEEE Workshop on Applications of Computer Vision (WACV),
  168-179. doi:10.1109/WACV.2013.6475015
"""

from __future__ import annotations

import colour
import numpy as np

from recon.errors import InputError

__all__ = ["jiang2013_response"]


def jiang2013_response(
    chart_rgb: np.ndarray,
    reflectances: np.ndarray,
    illuminant: np.ndarray,
    wavelengths: np.ndarray,
    training_responses: np.ndarray,
    *,
    components: int = 2,
) -> np.ndarray:
    """The response ``(K, 3)`` of Jiang et al. (2013) from one chart photograph.

    Parameters
    ----------
    chart_rgb
        ``(J, 3)`` linear device RGB of the chart's fields.
    reflectances
        ``(J, K)`` field reflectances on ``wavelengths``.
    illuminant
        ``(K,)`` relative spectral power of the light.
    wavelengths
        The ``K`` sample wavelengths in nm, regularly spaced.
    training_responses
        ``(N, K, 3)`` responses of measured cameras (not the one photographed) to learn the basis
        from.
    components
        Principal components per channel (Jiang et al. use two).

    Returns
    -------
    numpy.ndarray
        The response on ``wavelengths``, channels R, G, B, largest value one.

    References
    ----------
    Jiang et al. (2013): recovery from one photograph of a known chart under a known light.
    """
    wavelengths = np.asarray(wavelengths, np.float64)
    steps = np.diff(wavelengths)
    if wavelengths.ndim != 1 or wavelengths.size < 4 or not np.allclose(steps, steps[0]):
        raise InputError("wavelengths: expected at least 4 regularly spaced values in nm")
    reflectances = np.asarray(reflectances, np.float64)
    chart_rgb = np.asarray(chart_rgb, np.float64)
    training = np.asarray(training_responses, np.float64)
    bands = wavelengths.size
    if reflectances.ndim != 2 or reflectances.shape[1] != bands:
        raise InputError(f"reflectances: expected (fields, {bands}), got {reflectances.shape}")
    if chart_rgb.shape != (reflectances.shape[0], 3):
        raise InputError(f"chart_rgb: expected ({reflectances.shape[0]}, 3), got {chart_rgb.shape}")
    if np.shape(illuminant) != (bands,):
        raise InputError(f"illuminant: expected ({bands},), got {np.shape(illuminant)}")
    if training.ndim != 3 or training.shape[1:] != (bands, 3) or training.shape[0] <= components:
        raise InputError(
            f"training_responses: expected (cameras > {components}, {bands}, 3), "
            f"got {training.shape}"
        )
    if not 1 <= components < bands:
        raise InputError(f"components: expected 1 to {bands - 1}, got {components}")
    shape = colour.SpectralShape(wavelengths[0], wavelengths[-1], steps[0])
    cameras = {
        f"camera {index}": colour.MultiSpectralDistributions(
            response, wavelengths, labels=["R", "G", "B"]
        )
        for index, response in enumerate(training)
    }
    # (K, components) per channel, stacked as colour's basis_functions: (components, K, 3).
    basis = np.moveaxis(np.stack(colour.recovery.PCA_Jiang2013(cameras, components), -1), 1, 0)
    estimate = colour.recovery.RGB_to_msds_camera_sensitivities_Jiang2013(
        chart_rgb,
        colour.SpectralDistribution(np.asarray(illuminant, np.float64), wavelengths),
        colour.MultiSpectralDistributions(reflectances.T, wavelengths),
        basis,
        shape,
    )
    return np.asarray(estimate.values, np.float64)
