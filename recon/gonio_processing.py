"""Measurement run -> registered, calibrated spectral BTF (thesis 3.3 and 4.1.2).

For a capture store of one measurement run (``dark``, ``white`` and ``sample`` frames; the lamp
monitor with every lit frame) and the camera calibration (:mod:`recon.gonio_calibration`):

1. dark model of the run; :math:`F'_\\lambda` of the run from its white photographs (Eq. 3.6);
   the lamp monitor's mean spectrum over the white photographs is the drift reference;
2. per direction pair ``i``: linear signal per band :math:`\\hat f^{-1}(p) - \\hat f^{-1}(d)`,
   :math:`F_{i,long}` from the pair's monitor spectra, and Eq. 3.6,
   :math:`F'_\\lambda F_{i,long} \\hat f^{-1}(\\cdot) / t_\\lambda`; the white standard faced the
   lamp, so this is radiance over normal irradiance and is divided by :math:`\\cos\\theta_i` to
   give the BRDF in 1/sr;
3. registration of the pair on its band mean (:func:`recon.registration.register_frame`, with the
   rig's approximate corners to order them; where the sub-pixel refinement finds no corner, e.g.
   a border only two pixels wide at a grazing view, the coarse corners are kept and the pair is
   listed in the store's ``coarse_corner_pairs`` attribute), the texture square of the sample (a
   known fraction of the marks' square, centred) mapped to ``texels x texels`` (bilinear);
4. the texture written to the BTF store, pair by pair (an interrupted run resumes). Pairs whose
   border is not found at all are left unwritten and listed in ``unregistered_pairs``: give their
   corners in a manual corner file (keys ``"pair<i>"``) and process again with ``resume``.

The capture's ``rig`` attribute supplies the nominal directions (``light_dirs``, ``view_dirs``),
``expected_corners_xy``, ``sample_fraction``, ``white_view_id`` and the material's name.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hwbridge.store import CaptureStore
from recon.btf_store import BTFStore
from recon.corner_refinement import CornerRefinementError, texture_transform
from recon.errors import SpectwinInputError
from recon.gonio_calibration import GonioCalibration, dark_model, store_white_factors
from recon.progress import progress_steps
from recon.registration import (
    MarksNotFoundError,
    detect_corners,
    extract_texture,
    register_frame,
)
from recon.spectral_calibration import drift_factors, reflectance

__all__ = ["inset_corners", "process_gonio"]

_RIG_KEYS = (
    "light_dirs",
    "view_dirs",
    "expected_corners_xy",
    "sample_fraction",
    "white_view_id",
    "material",
)


def inset_corners(corners_xy: np.ndarray, fraction: float) -> np.ndarray:
    """Image corners of the centred sub-square of side ``fraction`` of the registered square
    (the sample inside its registration marks), through the marks' homography."""
    if not 0 < fraction <= 1:
        raise SpectwinInputError(f"sample_fraction: expected a fraction in (0, 1], got {fraction}")
    margin = (1 - fraction) / 2
    square = np.array([[0.0, 0.0], [1, 0], [1, 1], [0, 1]]) * fraction + margin
    return texture_transform(corners_xy).inverse(square)


def _rig(store: CaptureStore) -> dict:
    rig = store.attrs["rig"]
    missing = [key for key in _RIG_KEYS if key not in rig]
    if missing:
        raise SpectwinInputError(
            f"{store.path}: the capture's rig attribute lacks {missing}; expected a measurement "
            "run of the gonioreflectometer (spectwin capture --program gonio-run)"
        )
    return rig


def _pair_frames(
    store: CaptureStore, camera: str, index: dict, view: int, bands_nm: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Raw frames ``(K, H, W)`` of pair ``view`` in band order, their exposures and monitor
    spectra."""
    slots = np.flatnonzero((index["kind"] == "sample") & (index["view_id"] == view))
    slots = slots[np.argsort(index["band_nm"][slots])]
    if not np.allclose(index["band_nm"][slots], bands_nm):
        raise SpectwinInputError(
            f"{store.path}: pair {view} has bands {index['band_nm'][slots].tolist()}, the "
            f"calibration {bands_nm.tolist()}"
        )
    frames = store.frames(camera)
    stack = np.stack([frames[slot] for slot in slots])
    return stack, index["exposure_s"][slots], index["lamp_monitor"][slots]


def process_gonio(
    capture: str | Path | CaptureStore,
    calibration: GonioCalibration,
    out: str | Path,
    *,
    texels: int = 128,
    manual_corners: dict[str, np.ndarray] | None = None,
    resume: bool = False,
    show_progress: bool = False,
) -> BTFStore:
    """Turn a measurement run into a BTF store (see the module docstring).

    Parameters
    ----------
    capture
        The run's capture store (complete).
    calibration
        From :func:`recon.gonio_calibration.calibrate_gonio` (response curve, band grid).
    out
        BTF store to create (``<name>.btf.zarr``); with ``resume`` an existing one is continued.
    texels
        Texture resolution (texels per side of the sample).
    manual_corners
        Corner file contents (:func:`recon.registration.read_manual_corners`) keyed by
        ``"pair<i>"`` for frames where detection fails.
    """
    store = capture if isinstance(capture, CaptureStore) else CaptureStore.open(capture)
    rig = _rig(store)
    camera = str(rig.get("camera_id", "k4"))
    bands = calibration.bands_nm
    curve = calibration.inverse_response
    darks = dark_model(store, camera)
    white_bands, factors = store_white_factors(store, camera, darks, curve)
    if not np.allclose(white_bands, bands):
        raise SpectwinInputError(
            f"{store.path}: white photographs at {white_bands.tolist()} nm, the calibration has "
            f"{bands.tolist()} nm"
        )
    index = store.index(camera)
    reference = index["lamp_monitor"][index["kind"] == "white"].astype(np.float64).mean(axis=0)
    light_dirs = np.asarray(rig["light_dirs"], np.float64)
    view_dirs = np.asarray(rig["view_dirs"], np.float64)
    expected = np.asarray(rig["expected_corners_xy"], np.float64)
    if resume and Path(out).exists():
        btf = BTFStore.open(out, writable=True)
    else:
        btf = BTFStore.create(
            out,
            light_dirs=light_dirs,
            view_dirs=view_dirs,
            texels=texels,
            grid=calibration.grid,
            material=str(rig["material"]),
            source_capture=store.path,
            calibration={"run_factors": factors.tolist(), "source": calibration.source},
        )
    pending, coarse = btf.pending_pairs(), list(btf.attrs.get("coarse_corner_pairs", []))
    unregistered: list[int] = []
    with progress_steps("process", len(pending), enabled=show_progress) as advance:
        for pair in pending:
            frames, exposure, monitor = _pair_frames(store, camera, index, pair, bands)
            drift = drift_factors(np.vstack([reference, monitor.astype(np.float64).mean(axis=0)]))
            linear = darks.linear_signal(frames, exposure, curve)
            brdf = reflectance(linear, exposure, factors, drift=float(drift[1]))
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
                coarse.append(pair)
            except MarksNotFoundError:
                unregistered.append(pair)
                advance()
                continue
            texture = extract_texture(
                image, inset_corners(corners, float(rig["sample_fraction"])), resolution=texels
            )
            btf.write_pair(pair, texture, grid=calibration.grid, corners_xy=corners)
            advance()
    btf.set_attribute("coarse_corner_pairs", sorted(set(coarse)))
    btf.set_attribute("unregistered_pairs", unregistered)
    return btf
