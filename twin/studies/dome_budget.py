"""Where a dome store's texel errors come from: an error budget of the study's store path.

The stores' texels (:mod:`twin.studies.dome_stores`) err for four reasons at once: the spectral
reconstruction itself (Eq. 10.12 from three camera values and a few bands), the cameras'
sampling of the texture (pixels of a Bayer mosaic at an angle, demosaiced and resampled onto
the texels), the cameras' noise and everything else a render has that the truth has not (the
LED at a finite distance, the spectral camera's view 45 degrees away, the calibration's measured
spectra), and the registration of the holder's marks. The budget takes them in that order, each
rung adding one, every rung solved by the processing's own joint reconstruction
(:func:`recon.spectralize.reconstruct` over the run's images, its band schedule, band partner,
:data:`recon.dome.processing.P_DYN` and :data:`recon.dome.processing.SOLVER_TOLERANCE`):

1. ``reconstruction``: exact inputs: every image's :math:`V` the truth's, through the twin's
   camera model (:meth:`twin.dome.capture.DomeCameras.basis_rates`), and the scheduled bands
   the truth's, noise-free, unfiltered, reconstructed with the calibration's measured
   :math:`R_{cam}` (its error is this rung's too: at 16 texels, where few chart fields are
   resolved, 27 % on the colour checker against the analytic path's 9.8 %; at 64, 5.8 against
   7.5 %);
2. ``camera_sampling``: the same, noise-free, but seen through each camera's pixels: the truth
   with a texel a pixel of the top camera (:func:`fine_texels`,
   :func:`twin.render.truth.texture_truth`)
   averaged over every pixel where the camera's registration puts it, the RGB cameras' values
   mosaicked and demosaiced as the processing does
   (:func:`recon.calibration.dome_capture.rgb_linear_image`'s method), all resampled onto the
   texels by :meth:`recon.dome.images.TexelGrid.texture` (:func:`camera_sampled_texture`);
3. ``stores_true_marks``: the store processed with the marks where the rig's cameras truly
   image them (the store's nominal mark points, :func:`nominal_marks`): adds the noise, the
   HDR merge, the calibration and the render's lighting and views;
4. ``stores``: the store as :func:`recon.dome.processing.process_dome` processes it, the marks
   found in its frames: adds their registration.

Next to them, the analytic path (:func:`twin.dome.capture_study.simulate_capture`: one Bayer
quad per texel, aligned, with the cameras' noise, reconstructed with the twin's own response)
shows what noise adds without the cameras' sampling.
For rungs 2-4 the budget also gives the white-balanced :math:`V` 's own error against the
truth's (Eq. 6.8 on the three values), per RGB camera: the input the reconstruction gets.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from skimage import transform

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.store import CaptureStore
from recon.calibration.dome_capture import DomeCalibration
from recon.dome.images import TexelGrid
from recon.dome.processing import (
    SOLVER_TOLERANCE,
    DomeProcessing,
    band_weight,
    dome_directions,
    process_dome,
)
from recon.dome.run import DomeRun, open_dome_run
from recon.metrics import relative_error
from recon.progress import progress_steps
from recon.radiometric.demosaic import demosaic
from recon.registration.corners import texture_transform
from recon.spectralize.solve import BandImage, reconstruct
from twin.dome.capture_study import ReconstructionErrors
from twin.dome.setup import DomeSetup
from twin.render.truth import texture_truth
from twin.sensor.model import bayer_channel_index, mosaic_channels

if TYPE_CHECKING:
    from twin.studies.dome_stores import SameImages

__all__ = [
    "BUDGET_RUNGS",
    "camera_sampled_texture",
    "error_budget",
    "fine_texels",
    "nominal_marks",
]


def fine_texels(capture_texels: int, texels: int) -> int:
    """The truth's texels across the sample for the cameras' sampling (rung 2): one a pixel of
    the top camera, where a capture texel is a Bayer quad (twice the capture's texels), and at
    least two a texel; a multiple of ``texels``. Binned back, the fine truth matches the texel
    truth within its render noise (the colour checker at 4 per texel: 1.1 % mean Eq. 6.8 over
    the material texels).

    >>> fine_texels(64, 64), fine_texels(192, 64), fine_texels(16, 64)
    (128, 384, 128)
    """
    per_texel = max(2, -(-2 * capture_texels // texels))
    return per_texel * texels


BUDGET_RUNGS = ("reconstruction", "camera_sampling", "stores_true_marks", "stores")
"""The budget's rungs, each adding one source of error to the one before (module docstring)."""

_SUBPIXELS = 4  # samples per side of a pixel in camera_sampled_texture


def camera_sampled_texture(
    fine: np.ndarray, corners_xy: np.ndarray, grid: TexelGrid, *, mosaic: bool
) -> np.ndarray:
    """A texture ``fine`` ``(F, F, C)`` as a camera whose frame holds the sample's square at
    ``corners_xy`` delivers it to the texels of ``grid``, noise-free.

    Every pixel around the square averages the texture over ``4 x 4`` points of its area
    (nearest fine texel; outside the square the nearest border texel); with ``mosaic`` the
    pixels keep one channel each of an RGGB mosaic, demosaiced as the dome's processing
    demosaics (Malvar 2004); then the frame is resampled onto the texels as the processing
    resamples (:meth:`recon.dome.images.TexelGrid.texture`). Pixel centres at +0.5, as in
    :mod:`recon.registration`.
    """
    side = fine.shape[0]
    low = np.floor(corners_xy.min(axis=0)).astype(int) - 4
    low -= low % 2  # the mosaic's phase: RGGB from even rows and columns, as the frames
    width, height = np.ceil(corners_xy.max(axis=0)).astype(int) + 4 - low
    # output (sub-pixel index) -> frame point -> texture (u, v) -> fine texel index
    to_frame = np.array(
        [
            [1 / _SUBPIXELS, 0, low[0] + 0.5 / _SUBPIXELS],
            [0, 1 / _SUBPIXELS, low[1] + 0.5 / _SUBPIXELS],
            [0, 0, 1],
        ]
    )
    to_fine = np.array([[side, 0, -0.5], [0, side, -0.5], [0, 0, 1]])
    points = transform.warp(
        fine,
        transform.ProjectiveTransform(
            matrix=to_fine @ texture_transform(corners_xy).params @ to_frame
        ),
        output_shape=(height * _SUBPIXELS, width * _SUBPIXELS),
        order=0,
        mode="edge",
        preserve_range=True,
    )
    image = points.reshape(height, _SUBPIXELS, width, _SUBPIXELS, -1).mean(axis=(1, 3))
    if mosaic:
        raw = mosaic_channels(image, bayer_channel_index(height, width, "RGGB"))
        image = demosaic(raw, method="Malvar2004")
    return grid.texture(image, corners_xy - low)


def nominal_marks(run: DomeRun, work: DomeProcessing) -> dict[str, np.ndarray]:
    """Where every camera of the run truly images the holder's marks at every stage position
    (the rig's nominal mark points, ``marker_corners_xy``, pixel centres moved to +0.5), keyed
    and ordered as :func:`recon.dome.processing.process_dome`'s manual corners; ``work`` is
    registered already (its marks fix the order)."""
    cameras = run.rig.geometry.cameras
    marks = {}
    for (camera, view), registration in work.registrations.items():
        nominal = np.asarray(cameras[camera].marker_corners_xy[str(view)], np.float64) + 0.5
        nearest = [
            int(np.argmin(np.linalg.norm(nominal - point, axis=1)))
            for point in registration.expected_xy
        ]
        marks[f"{camera}_view{view}"] = nominal[nearest]
    return marks


@dataclass(frozen=True)
class _Images:
    """What every rung shares: the run, its registered processing, the truth's V and bands."""

    run: DomeRun
    work: DomeProcessing
    v_true: np.ndarray
    band_truth: np.ndarray


def _solve(images: _Images, v: np.ndarray, bands: np.ndarray) -> np.ndarray:
    """Eq. 10.12 over all the run's images (pairs in :func:`recon.dome.processing
    .dome_directions`' order) from ``v`` ``(n, H, W, 3)`` and, on the band partner's pairs, the
    scheduled bands of ``bands`` ``(n, H, W, K)``, unfiltered, weighed as the processing weighs
    them (:func:`recon.dome.processing.band_weight`)."""
    run, work = images.run, images.work
    cameras = run.rgb_cameras
    band_images = [
        BandImage(
            pair,
            band,
            bands[pair, ..., band],
            0.0,
            band_weight(v[pair], work.band_registration, work.target_relative_noise),
        )
        for image in range(len(run.images))
        for pair in [image * len(cameras) + cameras.index(work.partner)]
        for band in run.image_bands(image)
    ]
    return reconstruct(
        v,
        work.calibration.response,
        band_images=band_images,
        p_dyn=work.p_dyn,
        tol=SOLVER_TOLERANCE,
    ).spectra


def _camera_sampled(
    images: _Images, fine_v: np.ndarray, fine_bands: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Rung 2's inputs: every pair's V through its RGB camera, the partner pairs' bands through
    the spectral camera (:func:`camera_sampled_texture`)."""
    run, work = images.run, images.work
    cameras = run.rgb_cameras
    v = np.empty_like(images.v_true)
    bands = np.empty_like(images.band_truth)
    for image, (view, _) in enumerate(run.images):
        grid = work.grid(view)
        for index, camera in enumerate(cameras):
            pair = image * len(cameras) + index
            corners = work.registrations[camera, view].corners_xy
            v[pair] = camera_sampled_texture(fine_v[pair], corners, grid, mosaic=True)
            if camera == work.partner:
                spectral = work.registrations[SPECTRAL_CAMERA, view].corners_xy
                bands[pair] = camera_sampled_texture(fine_bands[pair], spectral, grid, mosaic=False)
    return v, bands


def _processed_v(images: _Images, store: CaptureStore, work: DomeProcessing) -> np.ndarray:
    """Every pair's white-balanced V as ``work`` makes it from the store."""
    run = images.run
    return np.stack(
        [
            work.rgb(store, image, camera)
            for image in range(len(run.images))
            for camera in run.rgb_cameras
        ]
    )


def error_budget(
    setup: DomeSetup,
    run_store: Path,
    calibration: DomeCalibration,
    found: SameImages,
    folder: Path,
    *,
    show_progress: bool = False,
) -> dict:
    """The budget of one material's store (module docstring): per rung the errors of
    :meth:`twin.dome.capture_study.ReconstructionErrors.summary` over the same groups as
    ``found`` (the store processed as it is, with the analytic path), and for rungs 2-4 per RGB
    camera the mean Eq. 6.8 error of V; per camera and stage position how far the marks found
    (or projected, ``found.projected_marks``) lie from where the camera truly images them;
    ``folder`` takes the BTF store of rung 3 while it is made. ``show_progress``: a bar over
    its steps (the truths, the cameras' sampling, rung 3's processing, the solves)."""
    with progress_steps("error budget", 5, enabled=show_progress) as advance:
        return _budget(setup, run_store, calibration, found, folder, advance)


def _budget(
    setup: DomeSetup,
    run_store: Path,
    calibration: DomeCalibration,
    found: SameImages,
    folder: Path,
    advance: Callable[[], None],
) -> dict:
    """:func:`error_budget`, calling ``advance`` after each of its five steps."""
    store = CaptureStore.open(run_store)
    run = open_dome_run(store)
    texels = found.truth.shape[1]
    work = DomeProcessing(run, calibration, texels, found.partner, p_dyn=found.p_dyn)
    work.register(store)
    light_dirs, view_dirs = dome_directions(run, calibration)
    truth = found.truth_texture
    fine_side = fine_texels(run.rig.texels, texels)
    fine = texture_truth(run.material, light_dirs, view_dirs, texels=fine_side, spp=16)
    white_rgb, _ = setup.cameras.white_rates()
    images = _Images(
        run,
        work,
        truth.weights @ setup.cameras.basis_rates(truth)[0] / white_rgb,
        found.truth,
    )
    fine_v = fine.weights @ setup.cameras.basis_rates(fine)[0] / white_rgb
    advance()
    sampled_v, sampled_bands = _camera_sampled(images, fine_v, setup.cameras.band_reflectance(fine))
    advance()
    true_marks = nominal_marks(run, work)
    btf_path = folder / f"{run.material}.true-marks.btf.zarr"
    shutil.rmtree(btf_path, ignore_errors=True)
    options = {"band_partner": found.partner, "p_dyn": found.p_dyn, "texels": texels}
    btf = process_dome(store, calibration, btf_path, manual_corners=true_marks, **options)
    marked = DomeProcessing(
        run, calibration, texels, found.partner, manual_corners=true_marks, p_dyn=found.p_dyn
    )
    marked.register(store)
    advance()
    cubes = {
        "reconstruction": _solve(images, images.v_true, images.band_truth),
        "camera_sampling": _solve(images, sampled_v, sampled_bands),
        "stores_true_marks": np.pi * btf.read(),
        "stores": found.stored,
    }
    advance()
    inputs = {
        "camera_sampling": sampled_v,
        "stores_true_marks": _processed_v(images, store, marked),
        "stores": _processed_v(images, store, work),
    }
    groups = found.groups()
    budget: dict = {"rungs": list(BUDGET_RUNGS), "fine_texels": fine_side}
    for rung in BUDGET_RUNGS:
        errors = ReconstructionErrors.of(cubes[rung], found.truth, found.shown)
        material = errors.material  # the same texels for every rung
        budget[rung] = errors.group_summaries(groups)
        if rung in inputs:
            v_error = relative_error(inputs[rung], images.v_true)
            budget[rung]["v_input_error_pct"] = {
                camera: float(v_error[indices][material[indices]].mean())
                if material[indices].any()
                else None
                for camera, indices in groups.items()
                if camera in run.rgb_cameras
            }
    names = {key: f"{key[0]}_view{key[1]}" for key in work.registrations}
    budget["marks_offset_from_nominal_px"] = {
        names[key]: float(np.linalg.norm(marks.marks_xy - true_marks[names[key]], axis=1).max())
        for key, marks in work.registrations.items()
    }
    shutil.rmtree(btf_path, ignore_errors=True)
    advance()
    return budget
