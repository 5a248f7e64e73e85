"""The LED dome as a kind of rig (thesis chapter 10): its capture programs, calibration (camera
geometry, the spectral camera's low-SNR calibration 10.3, RGB responses, white standard under
every LED), processing into a spectral BTF (Eq. 10.12, 10.4.2), evaluation against the twin's
truth and capture-time estimate.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import Field

from hwbridge.schema import recorded
from hwbridge.store import CaptureStore
from twin.kinds.kind import Outcome, ProgramKind, ProgramSettings, RigKind
from twin.rigs.rig_config import DomeConfig
from twin.studies.sweep_dome import check_dome_point, measure_dome_point
from twin.studies.sweep_file import SweepKind
from twin.studies.sweep_plans import DOME_MEASURES, DomePlan

__all__ = ["DOME", "DomeCalibrationSettings", "DomeRunSettings"]

DOME_CALIBRATION = Path("dome_cal.npz")
"""Where a dome calibration is written when no file is named."""


class DomeSettings(ProgramSettings):
    """What every dome program's size shares (:class:`twin.dome.programs.DomeCaptureSize`)."""

    leds: int = Field(198, ge=1, le=198, description="LEDs, spread over the dome.")
    rgb_cameras: int = Field(11, ge=1, le=11, description="RGB cameras, spread over the arc.")
    texels: int = Field(64, ge=4, le=1024, description="Texels across a 4 cm sample.")
    spp: int | None = Field(None, ge=1, le=65536, description="Samples per pixel of the renders.")
    led_renders: Literal["pose", "single"] = Field(
        "pose", description="LEDs of a stage position rendered together, or one at a time."
    )


class DomeCalibrationSettings(DomeSettings):
    """``dome-calibration``: darks, response series, white standard, checkerboard frames."""

    dark_frames: int = Field(200, ge=1, le=10000, description="Darks per spectral exposure.")


class DomeRunSettings(DomeSettings):
    """``dome-run``: the measurement of a material."""

    material: str = Field("colorchecker16", description="Material on the holder.")
    stage_positions: int = Field(24, ge=1, le=24, description="The first stage positions.")


def _size(settings: DomeSettings, stage_positions: int = 24):
    from twin.dome.programs import DEFAULT_SPP, DomeCaptureSize

    return DomeCaptureSize(
        stage_positions,
        settings.leds,
        settings.rgb_cameras,
        settings.texels,
        DEFAULT_SPP if settings.spp is None else settings.spp,
        settings.led_renders,
    )


def _run(settings: DomeRunSettings, fault_rate: float, dry_run: bool):
    from twin.dome.programs import dome_run_program

    size = _size(settings, settings.stage_positions)
    program = dome_run_program(
        settings.material, size=size, seed=settings.seed, fault_rate=fault_rate
    )
    return program, {}


def _calibration(settings: DomeCalibrationSettings, fault_rate: float, dry_run: bool):
    from twin.dome.programs import dome_calibration_program

    program = dome_calibration_program(
        size=_size(settings),
        dark_frames=settings.dark_frames,
        seed=settings.seed,
        fault_rate=fault_rate,
    )
    return program, {}


def _stored(capture: CaptureStore, model: type[DomeSettings]) -> Any:
    from twin.dome.programs import stored_dome_settings

    stored = stored_dome_settings(capture)
    return model(**{name: stored[name] for name in model.model_fields if name in stored})


def _calibrate(
    capture: CaptureStore, out: Path | None, options: dict[str, Any], show_progress: bool
) -> Outcome:
    from recon.calibration.dome_capture import calibrate_dome
    from recon.calibration.dome_spectra import response_weights
    from twin.studies.dome_figures import write_measured_spectra

    out = DOME_CALIBRATION if out is None else out
    calibration = calibrate_dome(capture, show_progress=show_progress)
    out.parent.mkdir(parents=True, exist_ok=True)
    calibration.save(out)
    summary: dict[str, object] = {
        "calibration": str(out),
        "bands": int(calibration.bands_nm.size),
        "leds": int(calibration.leds.size),
        "spectral_observed_levels": list(calibration.spectral.observed_levels),
    }
    led = calibration.led_spectrum
    summary["LED spectrum"] = (
        f"peak {led.wavelengths_nm[np.argmax(led.values)]:.0f} nm from {led.readings} "
        f"spectrometer readings, standard error at most {100 * led.uncertainty.max():.2f} % of "
        f"the peak, LED-to-LED spread at most {max(led.spread_pct.values(), default=0.0):.2f} %"
    )
    weights = response_weights(calibration.camera_response)
    for camera, measured in calibration.camera_response.items():
        peaks = calibration.bands_nm[np.argmax(measured.values, axis=0)]
        summary[f"{camera} response"] = (
            "peaks R {:.0f}, G {:.0f}, B {:.0f} nm; chart fit residual {:.1f} %; weight in "
            "R_cam {:.0f} %".format(*peaks, measured.fit_residual_pct, 100 * weights[camera])
        ) + ("; fields not resolved: their centre pixels" if measured.centre_pixels else "")
    figure = out.with_suffix(".spectra.png")
    write_measured_spectra(calibration, figure)
    summary["figure"] = str(figure)
    for camera, result in calibration.geometry.items():
        deviation = calibration.nominal_deviation[camera]
        summary[f"{camera} geometry"] = (
            f"{result.fitted} from {result.frames_used} of {result.frames_total} frames"
        )
        if result.reprojection_rms_px is not None:
            summary[f"{camera} reprojection_rms_px"] = result.reprojection_rms_px
        summary[f"{camera} position off nominal_mm"] = deviation["position_mm"]
        summary[f"{camera} orientation off nominal_deg"] = deviation["rotation_deg"]
    as_json = calibration.summary() | {"calibration": str(out), "figure": str(figure)}
    return Outcome("dome calibration", summary, as_json=as_json)


_SOLVE_OPTIONS = ("p_dyn", "band_registration")
"""``spectwin process`` options of the dome's joint solve, passed to
:func:`recon.dome.processing.process_dome` where given (its defaults otherwise) and recorded
with the BTF."""


def _process(
    capture: CaptureStore,
    calibration: Path,
    out: Path,
    options: dict[str, Any],
    show_progress: bool,
) -> Outcome:
    from hwbridge.lock import StoreLock
    from recon.btf.inputs import input_digests
    from recon.calibration.dome_capture import DomeCalibration
    from recon.dome.processing import check_dome_run, process_dome
    from recon.dome.run import open_dome_run

    dome_calibration = DomeCalibration.load(calibration)
    check_dome_run(open_dome_run(capture), dome_calibration)
    digests = input_digests(capture, calibration)
    resume = options.get("resume", False)
    lock = StoreLock.acquire(out) if resume and out.exists() else StoreLock.reserve(out)
    with lock:
        btf = process_dome(
            capture,
            dome_calibration,
            out,
            texels=options.get("texels"),
            manual_corners=options.get("manual_corners"),
            resume=resume,
            show_progress=show_progress,
            created=lambda _: lock.move_into(),
            digests=digests,
            **{name: options[name] for name in _SOLVE_OPTIONS if options.get(name) is not None},
        )
    found = btf.metadata
    summary = {
        "btf": str(out),
        "shape": list(btf.shape),
        "complete": btf.complete,
        "max_marks_offset_px": float(
            np.max(list(recorded(found.marks_offset_px, f"{out}: marks_offset_px").values()))
        ),
        "projected_marks": list(recorded(found.projected_marks, f"{out}: projected_marks")),
        "saturated_texels": found.saturated_texels,
    } | {name: (found.calibration or {}).get(name) for name in _SOLVE_OPTIONS}
    return Outcome("dome processing", summary)


def _evaluate(btf: Path, spp: int, figure: Path | None) -> Outcome:
    from twin.validate.dome_evaluation import evaluate_dome, write_dome_figure

    result = evaluate_dome(btf, spp=spp)
    summary = result.summary()
    if figure is not None:
        figure.parent.mkdir(parents=True, exist_ok=True)
        summary["figure"] = str(write_dome_figure(result, figure))
    return Outcome("dome BTF vs the twin's truth", summary)


def _estimate(config: DomeConfig) -> Outcome:
    from twin.dome.capture_time import estimate_dome

    return Outcome(f"capture time: {config.name}", estimate_dome(config).as_dict())


def _passbands(wavelengths_nm: np.ndarray):
    from twin.validate.dome_evaluation import spectral_passbands

    return spectral_passbands(wavelengths_nm)


DOME = RigKind(
    name="dome",
    config=DomeConfig,
    programs=(
        ProgramKind(
            "dome-calibration",
            DomeCalibrationSettings,
            _calibration,
            lambda capture: _stored(capture, DomeCalibrationSettings),
            fault_rate=True,
        ),
        ProgramKind(
            "dome-run",
            DomeRunSettings,
            _run,
            lambda capture: _stored(capture, DomeRunSettings),
            fault_rate=True,
        ),
    ),
    calibrate=_calibrate,
    process=_process,
    evaluate=_evaluate,
    estimate=_estimate,
    process_options=frozenset(_SOLVE_OPTIONS),
    sweep=SweepKind(DomeConfig, DomePlan, DOME_MEASURES, check_dome_point, measure_dome_point),
    calibration_file=DOME_CALIBRATION,
    calibration_suffix=".npz",
    passbands=_passbands,
)
"""The LED dome (``scenes/rigs/dome.yaml``)."""
