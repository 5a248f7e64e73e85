"""Measurement run -> registered, calibrated spectral BTF (thesis 3.3 and 4.1.2).

For a capture store of one measurement run (``dark``, ``white`` and ``sample`` frames; the lamp
monitor with every lit frame) and the camera calibration (:mod:`recon.calibration.gonio`):

1. dark model of the run; :math:`F'_\\lambda` of the run from its white photographs (Eq. 3.6);
   the lamp monitor's mean spectrum over the white photographs is the drift reference;
2. per direction pair ``i``: linear signal per band :math:`\\hat f^{-1}(p) - \\hat f^{-1}(d)`,
   :math:`F_{i,long}` from the pair's monitor spectra, and Eq. 3.6,
   :math:`F'_\\lambda F_{i,long} \\hat f^{-1}(\\cdot) / t_\\lambda`; the white standard faced the
   lamp, so this is radiance over normal irradiance and is divided by :math:`\\cos\\theta_i` to
   give the BRDF in 1/sr;
3. registration of the pair on its band mean (:func:`recon.registration.border.register_frame`,
with the
   rig's approximate corners to order them; where the sub-pixel refinement finds no corner, e.g.
   a border only two pixels wide at a grazing view, the coarse corners are kept and the pair is
   listed in the store's ``coarse_corner_pairs`` attribute), the texture square of the sample (a
   known fraction of the marks' square, centred) mapped to ``texels x texels`` (bilinear);
4. the texture written to the BTF store, pair by pair (an interrupted run resumes). Pairs whose
   border is not found at all are left unwritten and listed in ``unregistered_pairs``: give their
   corners in a manual corner file (keys ``"pair<i>"``) and process again with ``resume``.

The capture's ``rig`` attribute supplies the nominal directions (``light_dirs``, ``view_dirs``),
``expected_corners_xy``, ``sample_fraction``, ``white_view_id`` and the material's name.

:func:`process_gonio` does it all in one process. Its parts serve a distributed run
(``twin.devices.cluster``): :func:`prepare_gonio_run` (step 1, once) gives a :class:`GonioRun` that
pickles, :func:`open_btf_store` creates or reopens the BTF store, :func:`process_pairs` does steps
2 to 4 for any subset of pairs (in a worker, which owns those pairs' chunks), and
:func:`record_outcomes` stores which pairs were registered coarsely or not at all.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hwbridge.schema import GonioRigAttrs, recorded
from hwbridge.store import CaptureStore
from recon.btf.inputs import InputDigests, require_same_inputs
from recon.btf.store import BTFStore
from recon.calibration.gonio import (
    DarkModel,
    GonioCalibration,
    dark_model,
    store_white_factors,
)
from recon.calibration.spectral import drift_factors, reflectance
from recon.errors import InputError, Remedy
from recon.progress import progress_steps
from recon.registration.border import (
    MarksNotFoundError,
    detect_corners,
    extract_texture,
    register_frame,
)
from recon.registration.corners import CornerRefinementError, texture_transform

__all__ = [
    "DEFAULT_TEXELS",
    "GonioRun",
    "PairOutcomes",
    "check_gonio_run",
    "inset_corners",
    "open_btf_store",
    "prepare_gonio_run",
    "process_gonio",
    "process_pairs",
    "record_outcomes",
]

_INDEX_FIELDS = ("kind", "view_id", "band_nm", "exposure_s", "lamp_monitor")

DEFAULT_TEXELS = 128
"""Texels per side of a new BTF store when none are asked for."""


def inset_corners(corners_xy: np.ndarray, fraction: float) -> np.ndarray:
    """Image corners of the centred sub-square of side ``fraction`` of the registered square
    (the sample inside its registration marks), through the marks' homography."""
    if not 0 < fraction <= 1:
        raise InputError(f"sample_fraction: expected a fraction in (0, 1], got {fraction}")
    margin = (1 - fraction) / 2
    square = np.array([[0.0, 0.0], [1, 0], [1, 1], [0, 1]]) * fraction + margin
    return texture_transform(corners_xy).inverse(square)


def _rig(store: CaptureStore) -> GonioRigAttrs:
    rig = store.rig_attrs(GonioRigAttrs)
    if rig.program != "gonio-run":
        raise InputError(
            f"{store.path}: a capture of program {rig.program}; expected a measurement run of "
            "the gonioreflectometer (program gonio-run)",
            remedy=Remedy.capture_gonio_run,
        )
    return rig


def check_gonio_run(
    store: CaptureStore, calibration: GonioCalibration
) -> tuple[GonioRigAttrs, str, dict[str, np.ndarray]]:
    """Refuse a capture that is not a measurement run of the gonioreflectometer, or whose white
    photographs are at other bands than the calibration's: from the attributes and the index,
    before any frame is read. Returns the rig attribute, the camera id and the index."""
    rig = _rig(store)
    camera = rig.camera_id
    index = store.index(camera, _INDEX_FIELDS)
    white_bands = np.sort(index["band_nm"][index["kind"] == "white"].astype(np.float64))
    if white_bands.shape != calibration.bands_nm.shape or not np.allclose(
        white_bands, calibration.bands_nm
    ):
        raise InputError(
            f"{store.path}: white photographs at {white_bands.tolist()} nm, the calibration has "
            f"{calibration.bands_nm.tolist()} nm"
        )
    return rig, camera, index


@dataclass(frozen=True)
class GonioRun:
    """What processing needs of a measurement run, computed once (step 1 of the module
    docstring); plain data, so it travels to the workers of a distributed run.

    Attributes
    ----------
    capture_path
        The capture store (absolute), read pair by pair.
    camera
        The camera's id in the store.
    calibration
        The camera calibration.
    darks
        Dark model of the run.
    factors
        :math:`F'_\\lambda` of the run ``(K,)`` (Eq. 3.6).
    reference
        The lamp monitor's mean spectrum over the white photographs (the drift reference).
    index
        The index fields of the run's frames that pairs are selected by.
    rig
        The capture's ``rig`` attribute (a run's: its directions, marks and sample are set).
    """

    capture_path: Path
    camera: str
    calibration: GonioCalibration
    darks: DarkModel
    factors: np.ndarray
    reference: np.ndarray
    index: dict[str, np.ndarray]
    rig: GonioRigAttrs


@dataclass
class PairOutcomes:
    """Pairs whose corners were kept coarse and pairs left unregistered (no border found)."""

    coarse: list[int] = field(default_factory=list)
    unregistered: list[int] = field(default_factory=list)


def prepare_gonio_run(
    capture: str | Path | CaptureStore, calibration: GonioCalibration
) -> GonioRun:
    """Dark model, :math:`F'_\\lambda` and drift reference of a measurement run (step 1).

    Parameters
    ----------
    capture
        The run's capture store.
    calibration
        From :func:`recon.calibration.gonio.calibrate_gonio`; its bands must be the run's.

    Returns
    -------
    GonioRun
        Everything :func:`process_pairs` needs besides the frames.
    """
    store = capture if isinstance(capture, CaptureStore) else CaptureStore.open(capture)
    rig, camera, index = check_gonio_run(store, calibration)
    darks = dark_model(store, camera)
    _, factors = store_white_factors(store, camera, darks, calibration.inverse_response)
    reference = index["lamp_monitor"][index["kind"] == "white"].astype(np.float64).mean(axis=0)
    return GonioRun(
        capture_path=store.path.resolve(),
        camera=camera,
        calibration=calibration,
        darks=darks,
        factors=factors,
        reference=reference,
        index=index,
        rig=rig,
    )


def open_btf_store(
    run: GonioRun,
    out: str | Path,
    *,
    texels: int | None = None,
    resume: bool = False,
    digests: InputDigests | None = None,
) -> BTFStore:
    """Create the BTF store of ``run`` at ``out``; with ``resume`` an existing one is reopened
    (its pending pairs are still to process).

    Parameters
    ----------
    run
        From :func:`prepare_gonio_run`.
    out
        The BTF store.
    texels
        Texels per side: ``None`` is :data:`DEFAULT_TEXELS` for a new store, the store's own
        for a resumed one.
    resume
        Reopen an existing store.
    digests
        The hashes of the capture store and calibration file (:mod:`recon.btf.inputs`): a new
        store records them, a resumed one must have been made from the same.

    Raises
    ------
    InputError
        A resumed store was made from other inputs (:func:`recon.btf.inputs.require_same_inputs`).
    """
    if resume and Path(out).exists():
        btf = BTFStore.open(out, writable=True)
        require_same_inputs(btf, digests, texels)
        btf.prepare_resume()  # damaged pairs are pending again
        return btf
    texels = DEFAULT_TEXELS if texels is None else texels
    return BTFStore.create(
        out,
        light_dirs=np.asarray(run.rig.light_dirs, np.float64),
        view_dirs=np.asarray(run.rig.view_dirs, np.float64),
        texels=texels,
        grid=run.calibration.grid,
        material=str(run.rig.material),
        source_capture=run.capture_path,
        calibration={"run_factors": run.factors.tolist(), "source": run.calibration.source},
        rig=run.rig.rig,
        inputs=None if digests is None else digests.recorded(texels),
    )


def _pair_frames(
    store: CaptureStore, run: GonioRun, view: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Raw frames ``(K, H, W)`` of pair ``view`` in band order, their exposures and monitor
    spectra."""
    index, bands_nm = run.index, run.calibration.bands_nm
    slots = np.flatnonzero((index["kind"] == "sample") & (index["view_id"] == view))
    slots = slots[np.argsort(index["band_nm"][slots])]
    if not np.allclose(index["band_nm"][slots], bands_nm):
        raise InputError(
            f"{store.path}: pair {view} has bands {index['band_nm'][slots].tolist()}, the "
            f"calibration {bands_nm.tolist()}"
        )
    stack = store.read_frames(run.camera, slots)
    return stack, index["exposure_s"][slots], index["lamp_monitor"][slots]


def process_pairs(
    run: GonioRun,
    btf: BTFStore,
    pairs: Iterable[int],
    *,
    manual_corners: dict[str, np.ndarray] | None = None,
    check_complete: bool = True,
    advance: Callable[[], None] = lambda: None,
    stop: Callable[[], bool] = lambda: False,
    store: CaptureStore | None = None,
) -> PairOutcomes:
    """Calibrate, register and write ``pairs`` of ``run`` into ``btf`` (steps 2 to 4).

    Parameters
    ----------
    run
        From :func:`prepare_gonio_run`.
    btf
        From :func:`open_btf_store`, writable.
    pairs
        Direction pairs to process.
    manual_corners
        Corner file contents (:func:`recon.registration.border.read_manual_corners`) keyed by
        ``"pair<i>"`` for frames where detection fails.
    check_complete
        Mark the store complete after its last pair (``False`` in the workers of a distributed
        run, see :meth:`recon.btf.store.BTFStore.write_pair`).
    advance
        Called after each pair (a progress bar).
    stop
        Asked before each pair: when it says so the remaining pairs are left (for a resume).
    store
        The run's capture store, already open (``None``: opened from ``run.capture_path``, as
        a worker of a distributed run does).

    Returns
    -------
    PairOutcomes
        The pairs of ``pairs`` registered coarsely or not at all (those are left unwritten).
    """
    store = CaptureStore.open(run.capture_path) if store is None else store
    light_dirs = np.asarray(run.rig.light_dirs, np.float64)
    expected = np.asarray(run.rig.expected_corners_xy, np.float64)
    calibration = run.calibration
    outcomes = PairOutcomes()
    for pair in pairs:
        if stop():
            break
        frames, exposure, monitor = _pair_frames(store, run, pair)
        drift = drift_factors(np.vstack([run.reference, monitor.astype(np.float64).mean(axis=0)]))
        linear = run.darks.linear_signal(frames, exposure, calibration.inverse_response)
        brdf = reflectance(linear, exposure, run.factors, drift=float(drift[1]))
        image = np.moveaxis(brdf / light_dirs[pair, 2], 0, -1)
        try:
            corners = register_frame(
                image,
                frame_id=f"pair{pair}",
                manual_corners=manual_corners,
                expected_xy=expected[pair],
            )
        except CornerRefinementError:
            corners = detect_corners(image, expected_xy=expected[pair]).corners_xy
            outcomes.coarse.append(pair)
        except MarksNotFoundError:
            outcomes.unregistered.append(pair)
            advance()
            continue
        texture = extract_texture(
            image,
            inset_corners(
                corners,
                float(
                    recorded(run.rig.sample_fraction, f"{run.capture_path}: rig.sample_fraction")
                ),
            ),
            resolution=btf.texels[0],
        )
        btf.write_pair(
            pair,
            texture,
            grid=calibration.grid,
            corners_xy=corners,
            check_complete=check_complete,
        )
        advance()
    return outcomes


def record_outcomes(btf: BTFStore, outcomes: Iterable[PairOutcomes]) -> None:
    """Store the pairs of a processing pass that were registered coarsely (added to those of
    earlier passes) and those left unregistered (replacing the earlier list: they were retried)."""
    coarse = set(btf.metadata.coarse_corner_pairs or ())
    unregistered: list[int] = []
    for outcome in outcomes:
        coarse.update(outcome.coarse)
        unregistered += outcome.unregistered
    btf.set_attribute("coarse_corner_pairs", sorted(coarse))
    btf.set_attribute("unregistered_pairs", sorted(unregistered))


def process_gonio(
    capture: str | Path | CaptureStore,
    calibration: GonioCalibration,
    out: str | Path,
    *,
    texels: int | None = None,
    manual_corners: dict[str, np.ndarray] | None = None,
    resume: bool = False,
    show_progress: bool = False,
    digests: InputDigests | None = None,
) -> BTFStore:
    """Turn a measurement run into a BTF store (see the module docstring).

    Parameters
    ----------
    capture
        The run's capture store (complete).
    calibration
        From :func:`recon.calibration.gonio.calibrate_gonio` (response curve, band grid).
    out
        BTF store to create (``<name>.btf.zarr``); with ``resume`` an existing one is continued.
    texels
        Texture resolution (texels per side of the sample; ``None``: :data:`DEFAULT_TEXELS`,
        or a resumed store's own).
    manual_corners
        Corner file contents (:func:`recon.registration.border.read_manual_corners`) keyed by
        ``"pair<i>"`` for frames where detection fails.
    digests
        The hashes of the capture store and calibration file (:func:`open_btf_store`).
    """
    run = prepare_gonio_run(capture, calibration)
    btf = open_btf_store(run, out, texels=texels, resume=resume, digests=digests)
    pending = btf.pending_pairs()
    with progress_steps("process", len(pending), enabled=show_progress) as advance:
        outcomes = process_pairs(run, btf, pending, manual_corners=manual_corners, advance=advance)
    record_outcomes(btf, [outcomes])
    if not btf.complete:  # a run killed after its last pair's flag, before marking complete
        btf.refresh_complete()
    return btf
