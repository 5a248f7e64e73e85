"""Dome run -> spectral BTF store, without a renderer (thesis 10.1.2, 10.2.2, 10.4.2).

For a ``dome-run`` capture store and the dome's calibration
(:func:`recon.calibration.dome_capture.calibrate_dome`):

1. every camera is registered at every stage position on its alignment frame
   (:func:`recon.dome.images.register_view`);
2. the images of the run (stage position and LED) are reconstructed in groups, one cycle of the
   band schedule each (:func:`recon.dome.run.joint_groups`): every RGB camera's image of every
   LED of the group gives :math:`V` (:func:`recon.dome.images.white_balanced_rgb`); the spectral
   camera's scheduled bands of an LED, noisy reflectance factors
   (:func:`recon.dome.images.band_reflectance`, rectified where the partner sees the same
   surface: :func:`parallax_shift`), are matched to that LED's image from the RGB
   camera nearest the spectral camera's view (the same light; 10.2.2 places the spectral camera
   beside an RGB camera so that both see nearly the same), each after a Gaussian filter sized to
   its noise (:func:`band_sigma_px`, Figure 10.5), every texel weighed by how little a
   misregistration of the bands would change it there (:func:`band_weight`: dark lines beside
   bright ones weigh little); the group is solved jointly with Eq. 10.12 and
   the dynamic-range compression of Eq. 10.2 (:func:`recon.spectralize.reconstruct`), so the
   spectral data spread to the images and cameras without any (10.4.2);
3. every image of every RGB camera becomes a direction pair of the BTF store (reflectance
   factor / pi, in 1/sr), lit from the LED and seen from the calibrated camera, both in the
   sample frame, with the texture's corners in the camera's frame; the store is written group by
   group (an interrupted run resumes with the groups that have pending pairs).

Where a camera's marks are not found at a stage position (nor given in a manual corner file,
keys ``"<camera>_view<view_id>"``) the calibrated camera's projection of them stands in; the
BTF's ``projected_marks`` names those, ``marks_offset_px`` how far the marks found lie from
the projection everywhere.

References
----------
- The thesis, sections 10.1 (Eq. 10.1, 10.2, 10.12, 10.13), 10.2.2 and 10.4.2.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.store import CaptureStore
from recon.btf.inputs import InputDigests, require_same_inputs
from recon.btf.store import BTFStore
from recon.calibration.dome_capture import DomeCalibration
from recon.calibration.dome_geometric import CameraGeometry, stage_rotation
from recon.dome.images import (
    Registration,
    TexelGrid,
    band_reflectance,
    register_view,
    rgb_alignment_image,
    white_balanced_rgb,
)
from recon.dome.run import DomeRun, joint_groups, open_dome_run
from recon.errors import InputError, Remedy
from recon.progress import progress_steps
from recon.registration.corners import shifted_corners, texture_transform
from recon.scheduling.dome_schedule import FILTER_SIZE_PER_SIGMA, filter_sizes
from recon.spectralize.solve import BandImage, reconstruct

__all__ = [
    "BAND_REGISTRATION_TEXELS",
    "P_DYN",
    "SOLVER_TOLERANCE",
    "TARGET_RELATIVE_NOISE",
    "DomeProcessing",
    "band_sigma_px",
    "band_weight",
    "check_dome_run",
    "dome_directions",
    "PARALLAX_HEIGHTS_M",
    "ParallaxLine",
    "parallax_line",
    "parallax_shift",
    "process_dome",
    "spectral_partner",
]

P_DYN = 0.0
"""Eq. 10.2's exponent: no dynamic-range compression. The thesis found 0.5-0.6 best for BTFs, and
so does the analytic path of the twin's dome study for three materials of four (the same images
reconstructed 4-6 % better at 0.5 than at 0; the wallpaper equal). From the twin's dome capture
stores (one stage position x 10 LEDs x 3 RGB cameras, 32 texels, the calibration's measured
spectra; mean Eq. 6.8 with / without spectral data at 0, 0.5 and 0.6, BENCHMARKS.md "The dome's
spectra measured") 0 does better for three materials of four: colour checker 40.3 / 45.3, 41.1 /
45.8, 42.0 / 46.2 % (its diffuse fields 4.8, 5.2, 5.5 %), Lego 101 / 100, 108 / 104, 112 /
106 %, red fabric 296 / 364, 314 / 392, 333 / 412 %; the wallpaper 0.2-0.4 points worse (28.4
/ 34.5, 28.2 / 34.1, 28.3 / 34.1 %). The stores' errors come mostly from texels at edges and in
shadows (their edge-free texels do several times better, "Dome study from capture stores");
that the compression weighs those up is the likely cause, not separated further. ``spectwin
process --p-dyn`` chooses another."""

TARGET_RELATIVE_NOISE = 0.04
"""Relative noise the band filters leave. Figure 10.5's filters nearly cancel the noise; the
thesis found smaller ones often suffice, the prior of Eq. 10.12 smoothing what is left: on the
capture of :data:`P_DYN` filters for 0.04 (half as wide as for 0.02) took the diffuse fields
from 10.8 % to 9.1 %; narrower ones changed little (8.9 % for 0.08, 9.2 % without filters)."""

SOLVER_TOLERANCE = 1e-5
"""LSMR's stopping tolerance for a group's joint solve (``atol = btol`` of
:func:`recon.spectralize.reconstruct`, whose own default is 1e-6). On a 32-texel capture of 2
stage positions x 5 LEDs x 3 RGB cameras (``tests/integration/test_dome_processing.py``'s) the
colour checker's and the Lego's BTFs came out 0.23 % and 1.4 % of their largest value from the
1e-6 solution at most, their mean Eq. 6.8 against the twin's truth 9.182 % and 53.90 % against
9.185 % and 53.88 %, in 17-22 % less time (at 1e-4: 9.23 % and 54.02 %)."""

BAND_REGISTRATION_TEXELS = 0.25
"""How far (texels) the band data may lie from where the partner camera sees the same surface
after registration and the parallax shift (:func:`band_weight`). On the twin's dome study
stores (one stage position, 10 LEDs, captured at 192 texels, processed at 64) the colour
checker's bands lay 0.05-0.3 texels from the truth's, varying with the LED; weighed for 0.25
texels the stores came out better for all four materials (mean Eq. 6.8 with / without spectral
data, BENCHMARKS.md "The band data weighed by how well they are registered"): colour checker
19.9 / 26.2 -> 13.4 / 19.4 %, wallpaper 14.1 / 11.8 -> 13.5 / 11.6 %, Lego 64.5 / 71.3 -> 61.8 /
68.7 %, red fabric 137.7 / 167.5 -> 91.9 / 128.6 % (with the single rectification of
:meth:`DomeProcessing.bands`); 0.1-1 texels did within 1.2 points of each other on the colour
checker. 0 weighs every texel alike, as the thesis."""

_MAX_SIGMA_FRACTION = 0.25  # of the texture's side
_BRIGHTNESS_FLOOR = 1e-3  # of V, as recon.metrics.relative_error's eps


def band_sigma_px(
    values: np.ndarray, target_relative_noise: float = TARGET_RELATIVE_NOISE
) -> float:
    """Gaussian sigma (texels) for a noisy band image (Figure 10.5): its noise from the
    neighbouring texels' differences (robustly: their median absolute deviation, so edges of
    the texture count little), relative to its mean signal, through
    :func:`recon.scheduling.dome_schedule.filter_sizes` to ``target_relative_noise``;
    at most a quarter of the image's side."""
    differences = np.diff(np.asarray(values, np.float64), axis=1).ravel()
    noise = 1.4826 * np.median(np.abs(differences - np.median(differences))) / np.sqrt(2)
    mean = float(np.mean(values))
    if not mean > 0:
        return _MAX_SIGMA_FRACTION * values.shape[0]
    size = filter_sizes(np.array([noise / mean]), target_relative_noise)[0]
    return float(min(size / FILTER_SIZE_PER_SIGMA, _MAX_SIGMA_FRACTION * values.shape[0]))


def band_weight(
    partner_rgb: np.ndarray,
    registration_texels: float = BAND_REGISTRATION_TEXELS,
    target_relative_noise: float = TARGET_RELATIVE_NOISE,
) -> np.ndarray | None:
    """Per texel weight ``(H, W)`` of the band images' match (Eq. 10.1's first term) on the band
    partner's image :math:`V` ``partner_rgb`` ``(H, W, 3)``, or ``None`` (every texel alike,
    as the thesis) for ``registration_texels`` 0.

    A band value registered ``registration_texels`` off errs by about that many times its
    image's relative change per texel, which :math:`V` shows sharper and less noisy than the
    band: :math:`g` = half the range of :math:`V`'s brightness over the texel's 3 x 3
    neighbourhood, relative to its own. Against the noise the filters leave
    (``target_relative_noise``, :func:`band_sigma_px`) the weight is the ratio of standard
    deviations, :math:`1 / \\sqrt{1 + (\\sigma_{reg}\\, g / n)^2}`: 1 inside uniform regions,
    near 0 on a dark texel beside bright ones, whose band value a fraction of a texel's
    misregistration multiplies.

    Examples
    --------
    >>> v = np.full((5, 5, 3), 0.5)
    >>> v[:, 2] = 0.05  # a dark line one texel wide
    >>> np.round(band_weight(v)[2], 3)
    array([1.   , 0.335, 0.036, 0.335, 1.   ])
    >>> band_weight(v, 0.0) is None
    True
    """
    if registration_texels == 0:
        return None
    brightness = np.maximum(np.asarray(partner_rgb, np.float64).mean(axis=-1), _BRIGHTNESS_FLOOR)
    spread = ndimage.maximum_filter(brightness, size=3) - ndimage.minimum_filter(brightness, size=3)
    change = spread / 2 / brightness
    return 1 / np.sqrt(1 + (registration_texels * change / target_relative_noise) ** 2)


def check_dome_run(run: DomeRun, calibration: DomeCalibration) -> None:
    """Refuse a run the calibration does not fit (bands, frame size, cameras, LEDs), naming the
    difference, before any frame is read."""
    if run.bands_nm.shape != calibration.bands_nm.shape or not np.allclose(
        run.bands_nm, calibration.bands_nm
    ):
        raise InputError(
            f"{run.capture_path}: bands {run.bands_nm.tolist()} nm, the calibration's "
            f"{calibration.bands_nm.tolist()} nm"
        )
    if run.rig.window_px != calibration.window_px:
        raise InputError(
            f"{run.capture_path}: frames of {run.rig.window_px} px, the calibration's of "
            f"{calibration.window_px} px; expected a calibration at the run's texture size",
            remedy=Remedy.calibrate_texels,
        )
    cameras = sorted({*run.rgb_cameras, SPECTRAL_CAMERA} - set(calibration.geometry))
    if cameras:
        raise InputError(f"{run.capture_path}: cameras {cameras} are not calibrated")
    leds = sorted({light for _, light in run.images} - set(calibration.leds.tolist()))
    if leds:
        raise InputError(
            f"{run.capture_path}: LEDs {leds[:5]} have no white frames in the calibration; "
            "expected a calibration under the run's LEDs",
            remedy=Remedy.calibrate_leds,
        )


def dome_directions(run: DomeRun, calibration: DomeCalibration) -> tuple[np.ndarray, np.ndarray]:
    """Light and view directions ``(n_pairs, 3)`` in the sample frame: pair ``i`` is image
    ``i // n_cameras`` seen by RGB camera ``i % n_cameras``; the LED's position from the rig,
    the camera's from its calibration."""
    geometry = run.rig.geometry
    leds = np.asarray(geometry.led_positions_m, np.float64)
    angles = geometry.stage_angles_deg
    lights, views = [], []
    for view, light in run.images:
        to_sample = stage_rotation(angles[view]).T
        for camera in run.rgb_cameras:
            lights.append(to_sample @ leds[light])
            views.append(calibration.geometry[camera].geometry.position_in_sample(angles[view]))
    light_dirs, view_dirs = np.array(lights), np.array(views)
    return (
        light_dirs / np.linalg.norm(light_dirs, axis=1, keepdims=True),
        view_dirs / np.linalg.norm(view_dirs, axis=1, keepdims=True),
    )


PARALLAX_HEIGHTS_M = (-0.005, 0.02)
"""Heights of the sample's surface above the plate (m) over which :func:`parallax_shift`
searches: 5 mm below (a recessed sample) to 20 mm above (the twin's Lego bricks stand 9.6 mm
on their plate)."""

_PARALLAX_STEP_TEXELS = 0.05  # spacing of the shifts tried along the parallax line


@dataclass(frozen=True)
class ParallaxLine:
    """The shift ``(rows, columns)`` in texels that carries the spectral camera's texture onto
    its partner's where the sample's surface lies at height :math:`h` above the plate:
    ``offset + h * per_metre`` (both textures are rectified on the plate, :math:`h = 0`, so a
    surface above it moves with the view; ``offset``: what the two cameras' registrations
    leave at the plate itself)."""

    offset: np.ndarray
    per_metre: np.ndarray

    def shift(self, height_m: float) -> np.ndarray:
        """``(2,)`` the shift where the surface lies ``height_m`` above the plate."""
        return self.offset + height_m * self.per_metre


def parallax_line(
    cameras: Mapping[str, tuple[CameraGeometry, np.ndarray]], partner: str, texels: int
) -> ParallaxLine:
    """:class:`ParallaxLine` of the sample's centre from the calibrated ``partner`` and spectral
    camera, each with the image corners of its texture (``cameras``: camera -> (geometry,
    corners)), at ``texels`` texels: where each camera's rectification puts the centre lifted
    to 0 and to 1 mm (the stage turns about the centre, so its angle does not enter)."""

    def texel_rows_columns(camera: str, height_m: float) -> np.ndarray:
        geometry, corners = cameras[camera]
        image = geometry.project(np.array([[0.0, 0.0, height_m]])) + 0.5
        u, v = texture_transform(corners)(image)[0]
        return np.array([v, u]) * texels - 0.5

    def shift(height_m: float) -> np.ndarray:
        return texel_rows_columns(partner, height_m) - texel_rows_columns(SPECTRAL_CAMERA, height_m)

    return ParallaxLine(shift(0.0), (shift(1e-3) - shift(0.0)) / 1e-3)


def parallax_shift(
    partner: np.ndarray,
    spectral: np.ndarray,
    line: ParallaxLine,
    heights_m: tuple[float, float] = PARALLAX_HEIGHTS_M,
) -> np.ndarray:
    """The shift ``(rows, columns)`` in texels that carries the spectral camera's texture onto
    the partner's (both of the alignment frames, every LED on): the point of ``line`` within
    ``heights_m`` whose shifted texture correlates best with the partner's.

    Normalized cross-correlation over the texels no tried shift moves in from the border;
    shifts :data:`_PARALLAX_STEP_TEXELS` apart and at most a quarter of the texture's side (half
    of it is compared), the best refined by a parabola through its neighbours (none that short:
    the line's shift at the plate). What rises above the plate moves with the view (a 9.6 mm
    Lego brick's top by 3 texels at 32 texels between the spectral camera and the 37.5 degree
    RGB camera); thesis 10.1 registers the spectral images to the RGB images "using markers or
    other methods like optical flow". The search follows the line the view directions allow,
    not every shift: a texture that repeats (a weave, a printed pattern) correlates as well a
    period away, which an unconstrained peak (``skimage.registration.phase_cross_correlation``,
    the earlier way) took on the twin's red fabric at 64 texels: 11 texels off in columns
    (BENCHMARKS.md "Dome study from capture stores").
    """
    ends = [line.shift(height) for height in heights_m]
    count = int(np.ceil(np.abs(ends[1] - ends[0]).max() / _PARALLAX_STEP_TEXELS)) + 1
    heights = np.linspace(*heights_m, count)
    shifts = np.array([line.shift(height) for height in heights])
    short = np.abs(shifts).max(axis=1) <= min(partner.shape) / 4  # an interval of heights
    if not short.any():
        return line.shift(0.0)
    heights, shifts = heights[short], shifts[short]
    margin = int(np.ceil(np.abs(shifts).max())) + 1
    inner = (slice(margin, -margin), slice(margin, -margin))
    reference = partner[inner] - partner[inner].mean()

    def correlation(shift: np.ndarray) -> float:
        moved = ndimage.shift(spectral, shift, order=1, mode="nearest")[inner]
        moved = moved - moved.mean()
        return float((reference * moved).sum() / np.sqrt((reference**2).sum() * (moved**2).sum()))

    scores = np.array([correlation(shift) for shift in shifts])
    best = int(np.argmax(scores))
    if 0 < best < len(scores) - 1:
        left, centre, right = scores[best - 1 : best + 2]
        curvature = left - 2 * centre + right
        vertex = 0.5 * (left - right) / curvature if curvature < 0 else 0.0
        return line.shift(heights[best] + vertex * (heights[1] - heights[0]))
    return shifts[best]


def spectral_partner(run: DomeRun, calibration: DomeCalibration) -> str:
    """The RGB camera whose view lies nearest the spectral camera's."""
    positions = {c: r.geometry.position_m for c, r in calibration.geometry.items()}
    spectral = positions[SPECTRAL_CAMERA] / np.linalg.norm(positions[SPECTRAL_CAMERA])
    cosines = [spectral @ positions[c] / np.linalg.norm(positions[c]) for c in run.rgb_cameras]
    return run.rgb_cameras[int(np.argmax(cosines))]


@dataclass
class DomeProcessing:
    """A dome run being processed: the run, its calibration, the RGB camera whose images take
    the band data (:func:`spectral_partner`), and what registration found: per camera and
    stage position the marks, per stage position the band data's shift onto the partner's
    texture."""

    run: DomeRun
    calibration: DomeCalibration
    texels: int
    partner: str
    manual_corners: Mapping[str, np.ndarray] | None = None
    target_relative_noise: float = TARGET_RELATIVE_NOISE
    p_dyn: float = P_DYN
    band_registration: float = BAND_REGISTRATION_TEXELS
    registrations: dict[tuple[str, int], Registration] = field(default_factory=dict)
    band_shift: dict[int, np.ndarray] = field(default_factory=dict)
    saturated_texels: int = 0

    def grid(self, view: int) -> TexelGrid:
        angle = self.run.rig.geometry.stage_angles_deg[view]
        return TexelGrid(self.texels, self.run.sample_size_m, angle)

    def register(self, store: CaptureStore) -> None:
        """Register every camera at every stage position, and the spectral camera's texture
        onto the partner's (step 1)."""
        geometry = self.run.rig.geometry
        textures = {}
        for camera in (*self.run.rgb_cameras, SPECTRAL_CAMERA):
            for view in self.run.views:
                slot = self.run.slots(camera, "alignment", view)[:1]
                if slot.size == 0:
                    raise InputError(
                        f"{self.run.capture_path}: no alignment frame of camera {camera!r} at "
                        f"stage position {view}"
                    )
                frame = store.read_frames(camera, slot)[0]
                if camera == SPECTRAL_CAMERA:
                    exposure = float(self.run.index[camera]["exposure_s"][slot[0]])
                    image = self.calibration.spectral.linear_rate(frame, exposure)
                else:
                    image = rgb_alignment_image(self.calibration.rgb[camera], frame)
                self.registrations[camera, view] = register_view(
                    image,
                    self.calibration.geometry[camera].geometry,
                    geometry.holder,
                    geometry.stage_angles_deg[view],
                    self.run.sample_size_m,
                    frame_id=f"{camera}_view{view}",
                    manual_corners=self.manual_corners,
                )
                if camera in (self.partner, SPECTRAL_CAMERA):
                    corners = self.registrations[camera, view].corners_xy
                    textures[camera, view] = self.grid(view).texture(image, corners)
        for view in self.run.views:
            line = parallax_line(
                {
                    camera: (
                        self.calibration.geometry[camera].geometry,
                        self.registrations[camera, view].corners_xy,
                    )
                    for camera in (self.partner, SPECTRAL_CAMERA)
                },
                self.partner,
                self.texels,
            )
            self.band_shift[view] = parallax_shift(
                textures[self.partner, view], textures[SPECTRAL_CAMERA, view], line
            )

    def rgb(self, store: CaptureStore, image: int, camera: str) -> np.ndarray:
        """:math:`V` of one image of one RGB camera, saturated texels at the image's brightest
        finite value."""
        view, light = self.run.images[image]
        slots = self.run.slots(camera, "sample", view, light)
        times = self.run.index[camera]["exposure_s"][slots]
        order = [int(np.argmin(np.abs(self.calibration.rgb[camera].exposure_s - t))) for t in times]
        frames = store.read_frames(camera, slots[np.argsort(order)])
        values = white_balanced_rgb(
            self.calibration,
            camera,
            frames,
            self.registrations[camera, view].corners_xy,
            self.grid(view),
            light,
            np.asarray(self.run.rig.geometry.led_positions_m[light]),
        )
        saturated = ~np.isfinite(values)
        self.saturated_texels += int(saturated.any(axis=-1).sum())
        top = np.nanmax(np.where(saturated, np.nan, values).reshape(-1, 3), axis=0)
        return np.where(saturated, top, values)

    def bands(self, store: CaptureStore, image: int) -> list[tuple[int, np.ndarray]]:
        """``(band, noisy reflectance factors)`` of the spectral frames of one image, each
        rectified once at the sample's square moved by the stage position's parallax shift
        (:func:`recon.registration.corners.shifted_corners`): on the dome study's colour checker
        (captured at 192 texels, processed at 64) rectifying and then shifting the texture
        blurred its one-texel dark lines twice (their bands +85 % against the truth's, +63 %
        rectified once; the 30 images solved jointly 24.1 % mean Eq. 6.8 against 22.4 %)."""
        view, light = self.run.images[image]
        corners = shifted_corners(
            self.registrations[SPECTRAL_CAMERA, view].corners_xy, self.band_shift[view], self.texels
        )
        slots = self.run.slots(SPECTRAL_CAMERA, "sample", view, light)
        frames = store.read_frames(SPECTRAL_CAMERA, slots)
        position = np.asarray(self.run.rig.geometry.led_positions_m[light])
        index = self.run.index[SPECTRAL_CAMERA]
        return [
            (
                band,
                _nearest_inside(
                    band_reflectance(
                        self.calibration,
                        frame,
                        float(index["exposure_s"][slot]),
                        band,
                        corners,
                        self.grid(view),
                        light,
                        position,
                    )
                ),
            )
            for frame, slot, band in zip(frames, slots, self.run.image_bands(image), strict=True)
        ]


def _nearest_inside(texture: np.ndarray) -> np.ndarray:
    """``texture`` with the texels the shift moved off the frame (NaN) given the value of the
    nearest texel on it."""
    outside = ~np.isfinite(texture)
    if not outside.any():
        return texture
    nearest = ndimage.distance_transform_edt(outside, return_distances=False, return_indices=True)
    return texture[tuple(nearest)]


def _open_btf(
    work: DomeProcessing, out: Path, resume: bool, digests: InputDigests | None
) -> BTFStore:
    """The BTF store: created, recording ``digests``, or with ``resume`` an existing one
    reopened (its damaged pairs pending again), which must have been made from the same inputs
    at the texels asked for (:func:`recon.btf.inputs.require_same_inputs`)."""
    if resume and out.exists():
        btf = BTFStore.open(out, writable=True)
        require_same_inputs(btf, digests, work.texels)
        recorded_options = btf.metadata.calibration or {}
        for name in ("p_dyn", "band_registration"):
            begun = recorded_options.get(name, getattr(work, name))
            if begun != getattr(work, name):
                raise InputError(
                    f"{out}: begun with {name} {begun:g}; a resumed processing keeps it, got "
                    f"{getattr(work, name):g}"
                )
        btf.prepare_resume()
        return btf
    light_dirs, view_dirs = dome_directions(work.run, work.calibration)
    return BTFStore.create(
        out,
        light_dirs=light_dirs,
        view_dirs=view_dirs,
        texels=work.texels,
        grid=work.calibration.grid,
        material=work.run.material,
        source_capture=work.run.capture_path,
        calibration={
            "source": work.calibration.source,
            "rig": "dome",
            "p_dyn": work.p_dyn,
            "band_registration": work.band_registration,
            "target_relative_noise": work.target_relative_noise,
        },
        rig=work.run.rig.rig,
        inputs=None if digests is None else digests.recorded(work.texels),
    )


def _solve_group(
    work: DomeProcessing,
    store: CaptureStore,
    btf: BTFStore,
    group: list[int],
    solver: Mapping[str, Any],
    advance: Callable[..., None],
) -> None:
    """Reconstruct the images ``group`` jointly and write their pairs (step 2 and 3);
    ``advance`` once per image read and by the group's size once solved."""
    cameras = work.run.rgb_cameras
    shown = [(image, camera) for image in group for camera in cameras]
    rgb, band_images = [], []
    for image in group:
        rgb += [work.rgb(store, image, camera) for camera in cameras]
        partner = shown.index((image, work.partner))
        weight = band_weight(rgb[partner], work.band_registration, work.target_relative_noise)
        band_images += [
            BandImage(
                partner, band, values, band_sigma_px(values, work.target_relative_noise), weight
            )
            for band, values in work.bands(store, image)
        ]
        advance()
    cube = reconstruct(
        np.stack(rgb),
        work.calibration.response,
        band_images=band_images,
        p_dyn=work.p_dyn,
        **solver,
    ).spectra
    advance(len(group))
    for slot, (image, camera) in enumerate(shown):
        view, _ = work.run.images[image]
        btf.write_pair(
            image * len(cameras) + cameras.index(camera),
            cube[slot] / np.pi,
            grid=work.calibration.grid,
            corners_xy=work.registrations[camera, view].corners_xy,
        )


def process_dome(
    capture: str | Path | CaptureStore,
    calibration: DomeCalibration,
    out: str | Path,
    *,
    texels: int | None = None,
    manual_corners: Mapping[str, np.ndarray] | None = None,
    resume: bool = False,
    show_progress: bool = False,
    solver: Mapping[str, Any] | None = None,
    band_partner: str | None = None,
    target_relative_noise: float = TARGET_RELATIVE_NOISE,
    p_dyn: float = P_DYN,
    band_registration: float = BAND_REGISTRATION_TEXELS,
    created: Callable[[BTFStore], None] = lambda btf: None,
    digests: InputDigests | None = None,
) -> BTFStore:
    """Turn a dome run into a spectral BTF store (module docstring).

    Parameters
    ----------
    capture
        A complete ``dome-run`` capture store.
    calibration
        The dome's calibration (:func:`recon.calibration.dome_capture.calibrate_dome`, or a
        saved one: :meth:`~recon.calibration.dome_capture.DomeCalibration.load`).
    out
        BTF store to create; with ``resume`` an existing one is continued.
    texels
        Texels across the sample (default: the capture's ``texels``, or a resumed store's).
    manual_corners
        Corner file contents (:func:`recon.registration.border.read_manual_corners`) keyed by
        ``"<camera>_view<view_id>"``, for alignment frames whose marks are not found.
    resume
        Continue an interrupted processing: the groups with pending pairs are done again.
    show_progress
        Progress bars.
    solver
        Options of :func:`recon.spectralize.reconstruct` (``tol``, default
        :data:`SOLVER_TOLERANCE`, ``max_iterations``, ``solver``, ``appearance``, ...).
    band_partner
        The RGB camera whose images take the band data (default: the one whose view lies
        nearest the spectral camera's, :func:`spectral_partner`). Another camera moves the
        spectral data to another view, which separates the effect of spectral data on an image
        from that of its view (for diffuse materials, whose bands do not depend on the view).
    target_relative_noise
        The relative noise the band images' Gaussian filters leave (Figure 10.5's filter size;
        :func:`band_sigma_px`).
    p_dyn
        Eq. 10.2's exponent of the joint solve (default :data:`P_DYN`).
    band_registration
        How far (texels) the band data may lie from the partner's view of the same surface:
        texels where that would change them much weigh less (:func:`band_weight`; default
        :data:`BAND_REGISTRATION_TEXELS`, 0: every texel alike, as the thesis).
    created
        Called with the BTF store once it exists (before any pair is written): a writer lock
        moves into it.
    digests
        The hashes of the capture store and calibration file (:mod:`recon.btf.inputs`): a new
        store records them, a resumed one must have been made from the same.

    Returns
    -------
    BTFStore
        The store, complete.
    """
    store = capture if isinstance(capture, CaptureStore) else CaptureStore.open(capture)
    run = open_dome_run(store)
    check_dome_run(run, calibration)
    out = Path(out)
    if texels is None:
        existing = resume and out.exists()
        texels = BTFStore.open(out).texels[0] if existing else run.rig.texels
    if band_partner is None:
        band_partner = spectral_partner(run, calibration)
    elif band_partner not in run.rgb_cameras:
        raise InputError(
            f"band_partner: expected one of the run's RGB cameras {run.rgb_cameras}, got "
            f"{band_partner!r}"
        )
    if not 0 < target_relative_noise < 1:
        raise InputError(
            f"target_relative_noise: expected a fraction in (0, 1), got {target_relative_noise}"
        )
    if not 0 <= p_dyn <= 1:
        raise InputError(f"p_dyn: expected a value in [0, 1], got {p_dyn}")
    if not 0 <= band_registration <= 10:
        raise InputError(f"band_registration: expected 0 to 10 texels, got {band_registration}")
    work = DomeProcessing(
        run,
        calibration,
        int(texels),
        band_partner,
        manual_corners,
        target_relative_noise,
        p_dyn,
        band_registration,
    )
    btf = _open_btf(work, out, resume, digests)
    created(btf)
    work.register(store)
    pending = set(btf.pending_pairs())
    cameras = len(run.rgb_cameras)
    groups = [
        group
        for group in joint_groups(
            [run.image_bands(image) for image in range(len(run.images))],
            len(run.rig.band_schedule),
            run.bands_nm.size,
        )
        if any(image * cameras + c in pending for image in group for c in range(cameras))
    ]
    steps = 2 * sum(len(group) for group in groups)  # reading the images, then solving them
    options = {"tol": SOLVER_TOLERANCE, **(solver or {})}
    with progress_steps("process (read, solve)", steps, enabled=show_progress) as advance:
        for group in groups:
            _solve_group(work, store, btf, group, options, advance)
    registrations = {f"{camera}_view{view}": r for (camera, view), r in work.registrations.items()}
    btf.set_attribute("unregistered_pairs", [])
    btf.set_attribute("coarse_corner_pairs", [])
    btf.set_attribute(
        "projected_marks", sorted(name for name, r in registrations.items() if not r.found)
    )
    btf.set_attribute(
        "marks_offset_px", {name: r.marks_offset_px for name, r in registrations.items()}
    )
    btf.set_attribute(
        "dome_pairs",
        [[view, light, camera] for view, light in run.images for camera in run.rgb_cameras],
    )
    btf.set_attribute("saturated_texels", work.saturated_texels)
    btf.set_attribute("band_partner", work.partner)
    btf.set_attribute(
        "band_shift_texels", {str(view): shift.tolist() for view, shift in work.band_shift.items()}
    )
    return btf
