"""``spectwin calibrate`` and ``process`` of the LED dome's capture stores.

The commands of :mod:`twin.cli.gonio` hand a dome store (``rig == "dome"``) to these functions
(``evaluate`` tells a dome BTF by its ``dome_pairs``):

    spectwin capture out/cal.capture.zarr --program dome-calibration --leds 24 --rgb-cameras 3
    spectwin calibrate out/cal.capture.zarr --out out/dome_cal.npz
    spectwin capture out/lego.capture.zarr --program dome-run --material lego \\
        --stage-positions 2 --leds 24 --rgb-cameras 3
    spectwin process out/lego.capture.zarr --calibration out/dome_cal.npz --out out/lego.btf.zarr
    spectwin evaluate out/lego.btf.zarr --figure out/lego_vs_truth.png

The calibration and the run must share the reduced size's LEDs, RGB cameras and texels.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import numpy as np
import typer

from twin.cli.errors import INTERRUPTED, fail, require_output_file, require_output_folder
from twin.cli.output import print_summary
from twin.cli.store import require_sound_capture

__all__ = ["DEFAULT_CALIBRATION", "calibrate_dome_store", "process_dome_store"]

DEFAULT_CALIBRATION = Path("dome_cal.npz")
"""Where ``spectwin calibrate`` writes a dome calibration without ``--out``."""


def calibrate_dome_store(capture, store: Path, out: Path | None, as_json: bool) -> None:
    """Calibrate the dome from the calibration capture ``capture`` (opened from ``store``) into
    ``out`` (a ``.npz`` file): the options and the store's integrity checked first."""
    from recon.calibration.dome_capture import calibrate_dome

    out = DEFAULT_CALIBRATION if out is None else out
    if out.suffix != ".npz":
        fail(f"--out {out}: a dome calibration is an .npz file (it holds dark frames)")
    require_output_file(out)
    require_sound_capture(capture, store)
    calibration = calibrate_dome(capture, show_progress=not as_json)
    out.parent.mkdir(parents=True, exist_ok=True)
    calibration.save(out)
    summary: dict[str, object] = {
        "calibration": str(out),
        "bands": int(calibration.bands_nm.size),
        "leds": int(calibration.leds.size),
        "spectral_observed_levels": list(calibration.spectral.observed_levels),
    }
    for camera, result in calibration.geometry.items():
        deviation = calibration.nominal_deviation[camera]
        summary[f"{camera} geometry"] = (
            f"{result.fitted} from {result.frames_used} of {result.frames_total} frames"
        )
        if result.reprojection_rms_px is not None:
            summary[f"{camera} reprojection_rms_px"] = result.reprojection_rms_px
        summary[f"{camera} position off nominal_mm"] = deviation["position_mm"]
        summary[f"{camera} orientation off nominal_deg"] = deviation["rotation_deg"]
    if as_json:
        summary = calibration.summary() | {"calibration": str(out)}
    print_summary(summary, "dome calibration", as_json)


def process_dome_store(
    capture,
    store: Path,
    calibration: Path,
    out: Path,
    *,
    texels: int | None,
    manual_corners: Path | None,
    resume: bool,
    as_json: bool,
) -> None:
    """Process the dome run ``capture`` (opened from ``store``) into the BTF store ``out``: the
    calibration, the options and the store's integrity and fit checked first."""
    from hwbridge.lock import StoreLock
    from recon.calibration.dome_capture import DomeCalibration
    from recon.dome.processing import check_dome_run, process_dome
    from recon.dome.run import open_dome_run
    from recon.registration.border import read_manual_corners

    dome_calibration = DomeCalibration.load(calibration)
    corners = read_manual_corners(manual_corners) if manual_corners else None
    require_output_folder(out)
    require_sound_capture(capture, store)
    check_dome_run(open_dome_run(capture), dome_calibration)
    lock = StoreLock.acquire(out) if resume and out.exists() else StoreLock.reserve(out)
    try:
        with lock:
            btf = process_dome(
                capture,
                dome_calibration,
                out,
                texels=texels,
                manual_corners=corners,
                resume=resume,
                show_progress=not as_json,
                created=lambda _: lock.move_into(),
            )
    except KeyboardInterrupt:
        again = ["spectwin", "process", str(store), "--calibration", str(calibration)]
        typer.echo(
            f"interrupted; continue with: {shlex.join([*again, '--out', str(out), '--resume'])}",
            err=True,
        )
        raise typer.Exit(INTERRUPTED) from None
    attrs = btf.attrs
    offsets = [value for value in attrs["marks_offset_px"].values()]
    summary = {
        "btf": str(out),
        "shape": list(btf.shape),
        "complete": btf.complete,
        "max_marks_offset_px": float(np.max(offsets)),
        "projected_marks": attrs["projected_marks"],
        "saturated_texels": attrs["saturated_texels"],
    }
    print_summary(summary, "dome processing", as_json)
