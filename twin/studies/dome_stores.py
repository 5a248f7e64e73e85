"""The chapter 10 dome study from dome capture stores, processed as a real dome's are.

The study's store path takes its images where a real dome's processing would, through the same
code (:mod:`recon.dome`, :mod:`recon.calibration.dome_capture`):

1. :func:`capture_study_stores` renders a ``dome-calibration`` store (its full plan: the
   checkerboard frames, the response series, dark frames and the white standard under every
   LED) and per material a ``dome-run`` store (:mod:`twin.dome.programs`), where missing;
2. :func:`study_calibration` calibrates the dome from the calibration store
   (:func:`recon.calibration.dome_capture.calibrate_dome`: geometry, darks, low-SNR response,
   whites per LED), saved beside it;
3. :func:`same_images` processes a run into a BTF store
   (:func:`recon.dome.processing.process_dome`: the holder's marks, rectification, HDR merge,
   white balance per LED and texel, band reflectance, the joint solve of Eq. 10.12 over one cycle
   of the band schedule) and compares its pairs, as reflectance factors, with the analytic
   path's truth for the same light and view directions (:func:`twin.render.truth.texture_truth`
   in the spectral camera's bands); the analytic path (:func:`twin.dome.capture_study
   .simulate_capture`) takes the same images, LEDs and bands and is reconstructed with the same
   :data:`recon.dome.processing.P_DYN`, so that only the frames' path differs. Both are
   measured over the texels that show the sample's surface alone
   (:func:`twin.render.truth.surface_share`): seen from the side, the border of a raised sample
   shows its outer sides or, past its outline, the holder in a capture and nothing in the
   truth, a border :math:`h \\tan\\theta_v` deep (the wallpaper, 0.8 mm thick, at 75 degrees:
   5 texels of 64; the Lego's 11 mm bricks at 75 degrees: every texel);
4. :func:`store_exposure_ratio` takes 10.5's exposure totals from the run's exposures and the
   calibration's white standard.

Images (10.4.2): per stage position and LED one image per RGB camera; those of the camera
nearest the spectral camera (the processing's band partner) carry the bands the schedule gave
the LED, the others none.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.schema import DomeRigAttrs, recorded
from hwbridge.store import CaptureStore
from recon.calibration.dome import DARK_VALUE_OFFSET
from recon.calibration.dome_capture import DomeCalibration, calibrate_dome
from recon.dome.processing import P_DYN, dome_directions, process_dome
from recon.dome.run import open_dome_run
from recon.errors import InputError
from recon.metrics import relative_error
from recon.radiometric.hdr import interpolate_curve
from twin.dome.capture_study import ReconstructionErrors, reconstruct_capture, simulate_capture
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.dome.setup import BAND_GRID, DomeSetup, dome_setup
from twin.materials import load_material
from twin.materials.textures import TextureTruth
from twin.render.truth import surface_share, texture_truth
from twin.studies.dome_budget import error_budget as dome_error_budget
from twin.validate.dome_evaluation import chart_field_errors

__all__ = [
    "STORE_CAPTURE",
    "STORE_DARK_FRAMES",
    "TRUTH_SPP",
    "UNIFORM_TRUTH_PCT",
    "SameImages",
    "capture_study_stores",
    "material_stores",
    "same_images",
    "store_exposure_ratio",
    "store_study",
    "study_calibration",
    "top_camera",
    "uniform_texels",
    "view_fixed_shift",
]

STORE_CAPTURE = DomeCaptureSize(stage_positions=1, leds=10, rgb_cameras=3, texels=32)
"""The study's dome captures by default: one stage position, 10 LEDs spread over the dome (one
cycle of the 10-image band schedule), the RGB cameras at 0, 37.5 and 75 degrees and the spectral
camera, 32 texels (a Bayer quad per texel of a 4 cm sample), the capture's spp: 30 direction
pairs a material, solved jointly."""

STORE_DARK_FRAMES = 16
"""Dark frames per exposure time of the study's calibration capture (thesis 10.3: 200)."""

TRUTH_SPP = 1024
"""Samples a texel of the truth both paths are measured against. The red fabric's silver
threads and the Lego's studs give a truth of 64 samples 17 % and 8 % render noise per texel
(mean Eq. 6.8 against one of 1024 samples; the colour checker 1.1-1.4 %, the wallpaper
0.4-1.1 %), which the analytic path, taken from that truth, does not see and the stores do;
1024 samples take 4 min for the red fabric at 64 texels on 2 cores (the flat materials 40-50 s)."""

UNIFORM_TRUTH_PCT = 5.0
"""Largest Eq. 6.8 error (%) of any of a texel's eight neighbours' truth against its own for the
texel to count as edge-free (:func:`uniform_texels`). A texel resampled bilinearly is a weighted
mean of its 3 x 3 neighbourhood, its own weight at least a quarter where registration is good to
half a texel, so mixing adds at most three quarters of this, under 4 points, to its Eq. 6.8
error: below the analytic path's 5-18 % on the same images. The truth's own render noise is
below it (the colour checker's field interiors: 0 %)."""


def capture_study_stores(
    folder: Path,
    material: str,
    size: DomeCaptureSize,
    *,
    seed: int,
    dark_frames: int = STORE_DARK_FRAMES,
    calibration_spp: int | None = None,
    step: Callable[[str], None] = lambda name: None,
) -> tuple[Path, Path]:
    """The ``dome-run`` store of ``material`` and the ``dome-calibration`` store of ``size`` in
    ``folder``, captured where missing, resumed where incomplete; ``calibration_spp`` renders
    the calibration at other samples per pixel than ``size.spp`` (its targets are flat: at 4 the
    cameras' poses and spectra come out as at 16, ``tests/integration/test_dome_processing.py``)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = {
        "calibration": folder / "calibration.capture.zarr",
        material: folder / f"{material}.capture.zarr",
    }
    sizes = {
        "calibration": size if calibration_spp is None else replace(size, spp=calibration_spp),
        material: size,
    }
    programs = {
        "calibration": lambda: dome_calibration_program(
            size=sizes["calibration"], dark_frames=dark_frames, seed=seed
        ),
        material: lambda: dome_run_program(material, size=size, seed=seed),
    }
    for name, path in paths.items():
        if path.exists():
            _check_capture_size(path, sizes[name])
            if CaptureStore.open(path).complete:
                continue
        step(f"capturing the {name} store")
        programs[name]().run(path, resume=path.exists())
    return paths[material], paths["calibration"]


def material_stores(
    folder: Path,
    material: str,
    size: DomeCaptureSize,
    *,
    seed: int,
    step: Callable[[str], None],
) -> tuple[Path, Path]:
    """:func:`capture_study_stores` with its steps named after ``material``."""
    return capture_study_stores(
        folder, material, size, seed=seed, step=lambda name: step(f"{material}: {name}")
    )


def _check_capture_size(path: Path, size: DomeCaptureSize) -> None:
    """Refuse to reuse or resume a store captured at another size."""
    rig = CaptureStore.open(path).rig_attrs(DomeRigAttrs)
    wanted = asdict(size)
    recorded = {name: getattr(rig, name) for name in wanted}
    differing = [name for name, value in wanted.items() if recorded[name] not in (None, value)]
    if differing:
        raise InputError(
            f"{path}: captured with "
            + ", ".join(f"{name}={recorded[name]}" for name in differing)
            + "; expected "
            + ", ".join(f"{name}={wanted[name]}" for name in differing)
            + " (use another stores folder, or remove this store)"
        )


def uniform_texels(truth: np.ndarray, tolerance_pct: float = UNIFORM_TRUTH_PCT) -> np.ndarray:
    """``(n, H, W)``: the texels of ``truth`` (``(n, H, W, bands)``) whose eight neighbours'
    spectra are each within ``tolerance_pct`` of theirs by Eq. 6.8 (the neighbour taken as the
    estimate), the texels at the texture's border excluded: where rectification's resampling
    mixes in no other colour (:data:`UNIFORM_TRUTH_PCT`)."""
    height, width = truth.shape[1:3]
    centre = truth[:, 1:-1, 1:-1]
    worst = np.zeros(centre.shape[:-1])
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            neighbour = truth[:, 1 + dy : height - 1 + dy, 1 + dx : width - 1 + dx]
            worst = np.maximum(worst, relative_error(neighbour, centre))
    uniform = np.zeros(truth.shape[:-1], bool)
    uniform[:, 1:-1, 1:-1] = worst <= tolerance_pct
    return uniform


def study_calibration(calibration_store: Path) -> DomeCalibration:
    """The dome calibrated from ``calibration_store``, saved beside it (``.npz``) and reused."""
    saved = calibration_store.with_suffix(".npz")
    if saved.exists():
        return DomeCalibration.load(saved)
    calibration = calibrate_dome(calibration_store, show_progress=True)
    calibration.save(saved)
    return calibration


@dataclass(frozen=True)
class SameImages:
    """The images of a ``dome-run`` store processed from the store and taken by the analytic
    path (module description), ``(n_pairs, texels, texels, bands)`` reflectance factors each,
    with the truth (and the texture truth it is taken from, rendered with :data:`TRUTH_SPP`
    samples a texel), the texels that show the sample's surface alone (``shown``, ``(n_pairs,
    texels, texels)``, :func:`twin.render.truth.surface_share`: the errors count only these),
    the material, and per pair its view direction and RGB camera."""

    stored: np.ndarray
    analytic: np.ndarray
    truth: np.ndarray
    truth_texture: TextureTruth
    shown: np.ndarray
    material: str
    view_dirs: np.ndarray
    cameras: list[str]
    partner: str
    leds: list[int]
    projected_marks: list[str]
    p_dyn: float = P_DYN

    def groups(self) -> dict[str, list[int]]:
        """The pairs of each group the summaries take: ``with_spectral_data`` (the band
        partner's images), ``without_spectral_data`` (the other cameras') and each camera's."""

        def pairs(keep) -> list[int]:
            return [i for i, camera in enumerate(self.cameras) if keep(camera)]

        return {
            "with_spectral_data": pairs(lambda camera: camera == self.partner),
            "without_spectral_data": pairs(lambda camera: camera != self.partner),
        } | {name: pairs(lambda camera, name=name: camera == name) for name in self.cameras}

    def summary(self) -> dict:
        """Errors of both paths (:class:`twin.dome.capture_study.ReconstructionErrors`) with and
        without spectral data and per RGB camera, over the material texels, under
        ``"edge_free"`` over the material texels whose truth is uniform over their 3 x 3
        neighbourhood (:func:`uniform_texels`; the same texels for both paths) and, for a chart,
        under ``"diffuse_fields"`` the means of its diffuse fields' interiors (60 %) against the
        truth's (:func:`twin.validate.dome_evaluation.chart_field_errors`, as ``spectwin
        evaluate``): on both a fraction of a texel of resampling or registration changes
        little. ``"edge_free_texels"``: per group the share of the material texels kept and
        their number (none: the group's errors are ``None``)."""

        groups = self.groups()
        material = load_material(self.material)
        chart = any(part.name.startswith("field_") for part in material.parts)
        errors = {
            name: ReconstructionErrors.of(cube, self.truth, self.shown)
            for name, cube in (("stores", self.stored), ("analytic", self.analytic))
        }
        material_texels = errors["analytic"].material
        edge_free = material_texels & uniform_texels(self.truth)
        out: dict = {
            "edge_free_texels": {
                group: {
                    "count": int(edge_free[indices].sum()),
                    "fraction_of_material": float(
                        edge_free[indices].sum() / max(material_texels[indices].sum(), 1)
                    ),
                }
                for group, indices in groups.items()
            }
        }
        for name, cube in (("stores", self.stored), ("analytic", self.analytic)):
            out[name] = errors[name].group_summaries(groups)
            out[name]["edge_free"] = replace(errors[name], material=edge_free).group_summaries(
                groups
            )
            if chart:
                relative, colour, *_ = chart_field_errors(
                    material, self.view_dirs, cube, self.truth, BAND_GRID, 0.6
                )
                out[name]["diffuse_fields"] = {
                    group: {
                        "mean_relative_error_pct": float(np.nanmean(relative[indices])),
                        "mean_delta_e94": float(np.nanmean(colour[indices])),
                    }
                    for group, indices in groups.items()
                }
        out["images"] = {
            "leds": self.leds,
            "cameras": list(dict.fromkeys(self.cameras)),
            "band_partner": self.partner,
            "texels": self.truth.shape[1],
            "p_dyn": self.p_dyn,
            "projected_marks": self.projected_marks,
        }
        return out


def same_images(
    setup: DomeSetup,
    run_store: Path,
    calibration: DomeCalibration,
    btf_path: Path,
    rng: np.random.Generator,
    *,
    band_partner: str | None = None,
    p_dyn: float = P_DYN,
    truth_of: SameImages | None = None,
) -> SameImages:
    """A ``dome-run`` store processed into ``btf_path`` and its images taken by the analytic
    path with ``setup`` (module description); the band data on the images of ``band_partner``
    (default: the RGB camera nearest the spectral camera) in both paths, both solved with Eq.
    10.2's exponent ``p_dyn``; the truth and the texels shown those of ``truth_of`` (the same
    run processed before) where given, else rendered."""
    run = open_dome_run(run_store)
    texels = setup.cameras.spectral.height // setup.cameras.pixels_per_texel
    shutil.rmtree(btf_path, ignore_errors=True)
    btf = process_dome(
        run_store,
        calibration,
        btf_path,
        texels=texels,
        show_progress=True,
        band_partner=band_partner,
        p_dyn=p_dyn,
    )
    found = btf.metadata
    partner = recorded(found.band_partner, f"{btf.path}: band_partner")
    cameras = [camera for _ in run.images for camera in run.rgb_cameras]
    bands = [
        run.image_bands(image) if camera == partner else []
        for image in range(len(run.images))
        for camera in run.rgb_cameras
    ]
    light_dirs, view_dirs = dome_directions(run, calibration)
    if truth_of is None:
        truth = texture_truth(run.material, light_dirs, view_dirs, texels=texels, spp=TRUTH_SPP)
        shown = surface_share(load_material(run.material), view_dirs, texels=texels) >= 1
    else:
        truth, shown = truth_of.truth_texture, truth_of.shown
    analytic = simulate_capture(setup, truth, light_dirs, bands, rng)
    stored = np.pi * btf.read()
    return SameImages(
        stored.astype(np.float64),
        reconstruct_capture(setup, analytic, p_dyn=p_dyn),
        analytic.truth,
        truth,
        shown,
        run.material,
        view_dirs,
        cameras,
        partner,
        [light for _, light in run.images],
        list(recorded(found.projected_marks, f"{btf.path}: projected_marks")),
        p_dyn,
    )


def top_camera(images: SameImages) -> str:
    """The RGB camera other than the band partner whose view lies nearest the sample's normal."""
    others = [camera for camera in dict.fromkeys(images.cameras) if camera != images.partner]
    cameras = np.array(images.cameras)
    return max(others, key=lambda camera: float(images.view_dirs[cameras == camera, 2].mean()))


def view_fixed_shift(nearest: dict, moved: dict) -> dict:
    """10.4.2's shift from images with spectral data to images without, camera by camera: the
    summaries (:meth:`SameImages.summary`) of one run processed with the band data on the
    partner nearest the spectral camera (``nearest``) and on another camera (``moved``). Each of
    the two partners' images is then once with and once without band data, at the same view
    and light: per source (stores, analytic) and texel set (all material texels, edge-free),
    per partner camera the two means of Eq. 6.8 and of Delta E94."""
    partners = {
        nearest["images"]["band_partner"]: (nearest, moved),
        moved["images"]["band_partner"]: (moved, nearest),
    }
    shift: dict = {}
    for source in ("stores", "analytic"):
        for scope in ("all", "edge_free"):
            entry = shift.setdefault(source, {}).setdefault(scope, {})
            for camera, (with_bands, without) in partners.items():
                pair = [
                    (summary[source] if scope == "all" else summary[source]["edge_free"])[camera]
                    for summary in (with_bands, without)
                ]
                entry[camera] = (
                    None
                    if None in pair
                    else {
                        measure: {"with": pair[0][measure], "without": pair[1][measure]}
                        for measure in ("mean_relative_error_pct", "mean_delta_e94")
                    }
                )
    return shift


def store_exposure_ratio(run_store: Path, calibration: DomeCalibration) -> dict[str, float]:
    """Thesis 10.5's exposure totals from the stores: the hybrid image (the run's HDR set and
    every band at the run's exposures, one after the other) against spectral-only band frames
    that bring the white standard facing the LED to 80 % of the spectral camera's range (its
    rate per band from the calibration, :math:`E_\\lambda L_\\lambda \\rho_\\lambda`; the range
    in the calibrated curve's units above the averaged dark level)."""
    rig = CaptureStore.open(run_store).rig_attrs(DomeRigAttrs)
    spectral = calibration.spectral
    full_scale_dn = 2 ** rig.geometry.cameras[SPECTRAL_CAMERA].bit_depth - 1
    dark = float(np.median(spectral.mean_dark_frames))
    headroom = float(
        interpolate_curve(
            spectral.inverse_response,
            np.array([full_scale_dn - dark + DARK_VALUE_OFFSET, DARK_VALUE_OFFSET]),
        )
        @ np.array([1.0, -1.0])
    )
    white_rate = spectral.sensitivity * calibration.led_per_band * calibration.white_per_band
    reference_s = float((0.8 * headroom / white_rate).sum())
    hybrid_s = float(sum(rig.rgb_exposures_s) + sum(rig.band_exposures_s))
    return {
        "hybrid_total_s": hybrid_s,
        "reference_total_s": reference_s,
        "orders_of_magnitude": math.log10(reference_s / hybrid_s),
    }


def store_study(
    folder: Path,
    materials: Sequence[str],
    size: DomeCaptureSize = STORE_CAPTURE,
    *,
    seed: int,
    step: Callable[[str], None] = lambda name: None,
    error_budget: bool = False,
    texels: int | None = None,
) -> dict:
    """The store path of the dome study (module description): per material its ``dome-run``
    store, one calibration store, the multi-image experiment (processed twice: with the band
    data on the RGB camera nearest the spectral camera and on the top camera, for
    :func:`view_fixed_shift`), and the 10.5 exposure totals; with ``error_budget`` per material
    under ``"error_budget"`` where its errors come from
    (:func:`twin.studies.dome_budget.error_budget`). The runs are processed at ``texels``
    (default the captures' own, a Bayer quad a texel at the top camera; fewer: each texel
    spans more of every camera's pixels)."""
    processed = size.texels if texels is None else texels
    if not 4 <= processed <= size.texels:
        raise InputError(
            f"texels: expected 4 to the captures' {size.texels} texels, got {processed}"
        )
    setup = dome_setup(processed, texel_px=2, seed=seed)
    rng = np.random.default_rng(seed)
    result: dict = {"capture": size.__dict__, "folder": str(folder), "materials": {}}
    calibration = None
    for material in materials:
        run_store, calibration_store = material_stores(folder, material, size, seed=seed, step=step)
        if calibration is None:
            step("calibrating the dome from its calibration store")
            calibration = study_calibration(calibration_store)
        step(f"{material}: processing the run store")
        nearest = same_images(setup, run_store, calibration, folder / f"{material}.btf.zarr", rng)
        summary = nearest.summary()
        if error_budget:
            step(f"{material}: the error budget")
            summary["error_budget"] = dome_error_budget(
                setup, run_store, calibration, nearest, folder, show_progress=True
            )
        moved_to = top_camera(nearest)
        step(f"{material}: processing the run store with the band data on {moved_to}")
        moved = same_images(
            setup,
            run_store,
            calibration,
            folder / f"{material}.bands-{moved_to}.btf.zarr",
            rng,
            band_partner=moved_to,
            truth_of=nearest,
        ).summary()
        summary["view_fixed_shift"] = view_fixed_shift(summary, moved)
        result["materials"][material] = summary
    if calibration is None:
        raise InputError("materials: expected at least one material")
    result["exposure_10_5"] = store_exposure_ratio(run_store, calibration)
    return result
