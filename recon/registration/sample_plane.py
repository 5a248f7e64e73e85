"""The sample's square on the holder's plate in a dome frame, from the registration marks.

The dome's cameras see the sample holder of the gonioreflectometer (thesis 4.1.2, 10.2.2): the
outer corners of its black print are found in a frame with every LED on
(:func:`recon.registration.border.register_frame`), and the homography of the print's plane
carries the sample's square into the image, where :func:`recon.registration.border
.extract_texture` samples the texture. The print lies a fraction of a millimetre above the plate
on which the material rests (z = 0 of the sample frame: the plane of the texture, and of the
twin's truth); at 75 degrees from the normal 0.2 mm shift the image by 0.8 mm, more than a texel
at 64 texels, so the square's corners on z = 0 are first carried along the camera's rays up to
the print's plane (:func:`sample_square_corners`).

Texture layout (the twin's truth's): texel ``(i, j)`` of ``n`` lies at
:math:`x = -s/2 + (j + 0.5) s/n`, :math:`y = s/2 - (i + 0.5) s/n` on the plate of a sample of
side :math:`s`; texture corner ``(0, 0)`` is :math:`(-s/2, s/2)`.

References
----------
- The thesis, sections 4.1.2 (the border's homography to texture space) and 10.2.2 (the holder
  detected with sub-pixel accuracy in an image with several LEDs on, at every stage position).
"""

from __future__ import annotations

import numpy as np
from skimage import transform

from recon.errors import InputError
from recon.registration.corners import validate_corners

__all__ = ["sample_square_corners", "texel_centres_m"]


def texel_centres_m(texels: int, sample_size_m: float) -> np.ndarray:
    """``(texels, texels, 2)`` the texels' centres ``(x, y)`` on the plate, sample frame.

    Examples
    --------
    >>> texel_centres_m(2, 0.04)[0].round(12).tolist()
    [[-0.01, 0.01], [0.01, 0.01]]
    """
    centres = (np.arange(texels) + 0.5) / texels * sample_size_m - sample_size_m / 2
    x, y = np.meshgrid(centres, -centres)
    return np.stack([x, y], axis=-1)


def sample_square_corners(
    marks_xy: np.ndarray,
    marks_m: np.ndarray,
    camera_position_m: np.ndarray,
    sample_size_m: float,
) -> np.ndarray:
    """Image corners of the sample's square on the plate, in texture order (module docstring).

    Parameters
    ----------
    marks_xy
        ``(4, 2)`` the registration corners found in the frame, in texture order, pixel
        centres at +0.5 (:func:`recon.registration.border.register_frame`).
    marks_m
        ``(4, 3)`` the same corners in the sample frame (the print's plane, z > 0).
    camera_position_m
        ``(3,)`` the camera's projection centre in the sample frame.
    sample_size_m
        The side of the sample's square, centred on the plate.

    Returns
    -------
    numpy.ndarray
        ``(4, 2)`` image corners of :math:`(-s/2, s/2), (s/2, s/2), (s/2, -s/2), (-s/2, -s/2)`
        on z = 0, for :func:`recon.registration.border.extract_texture`.

    Examples
    --------
    >>> marks = np.array([[-1.0, 1, 0.1], [1, 1, 0.1], [1, -1, 0.1], [-1, -1, 0.1]])
    >>> image = (marks[:, :2] * [1, -1] + 1) * 50  # a camera straight above, 50 px per m
    >>> corners = sample_square_corners(image, marks, np.array([0.0, 0, 10]), 1.0)
    >>> corners.round(3).tolist()[0]  # (-0.5, 0.5) on z = 0 is seen at (-0.495, 0.495) on z = 0.1
    [25.25, 25.25]
    """
    image = validate_corners(marks_xy, "marks_xy")
    marks = np.asarray(marks_m, np.float64)
    centre = np.asarray(camera_position_m, np.float64)
    if marks.shape != (4, 3) or centre.shape != (3,) or not centre[2] > marks[:, 2].max():
        raise InputError(
            f"marks_m, camera_position_m: expected (4, 3) marks below a camera (3,), got "
            f"{marks.shape} and {centre.tolist()}"
        )
    if not 0 < sample_size_m < 2 * np.abs(marks[:, :2]).max():
        raise InputError(
            f"sample_size_m: expected a square inside the marks, got {sample_size_m} m"
        )
    homography = transform.ProjectiveTransform.from_estimate(marks[:, :2], image)
    if not homography:
        raise InputError(f"marks_xy: no homography for {image.tolist()}")
    half = sample_size_m / 2
    square = np.array([[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]])
    along_rays = square + (marks[:, 2].mean() / centre[2]) * (centre - square)
    return homography(along_rays[:, :2])
