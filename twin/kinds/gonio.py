"""The spectral gonioreflectometer as a kind of rig (thesis 3.3, 4.1): its capture programs,
calibration (Robertson response, white factors Eq. 3.3, exposure plan Eq. 3.4), processing into a
BTF (Eq. 3.6, 4.1.2), evaluation against the twin's truth and capture-time estimate.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from hwbridge.schema import recorded
from hwbridge.store import CaptureStore
from recon.errors import InputError
from twin.kinds.kind import Outcome, ProgramKind, ProgramSettings, RigKind
from twin.output_format import format_pairs
from twin.rigs.rig_config import GonioConfig
from twin.studies.sweep_file import SweepKind
from twin.studies.sweep_gonio import check_gonio_point, measure_gonio_point
from twin.studies.sweep_plans import GONIO_MEASURES, GonioPlan

if TYPE_CHECKING:
    from twin.gonio.capture import CaptureProgram

__all__ = ["GONIO", "GonioCalibrationSettings", "GonioRunSettings"]

NAME = "gonioreflectometer"
GONIO_CALIBRATION = Path("cal.json")
"""Where a gonio calibration is written when no file is named."""


class GonioCalibrationSettings(ProgramSettings):
    """``gonio-calibration``: darks, response series, white standard."""


class GonioRunSettings(ProgramSettings):
    """``gonio-run``: a measurement run of a material over a direction sampling."""

    material: str = Field("colorchecker16", description="Material on the holder.")
    pixels: int = Field(256, ge=32, le=4096, description="Pixels across the 20 cm field.")
    window: int | None = Field(
        None, ge=16, le=4096, description="Centred read-out window (None: the whole field)."
    )
    sampling: Literal["reduced", "glossy"] | None = Field(
        "reduced", description="The direction sampling (None: the store's own pairs)."
    )
    spp: int | None = Field(None, ge=1, le=65536, description="Samples per pixel of the renders.")
    exposures_s: tuple[float, ...] | None = Field(
        None, description="Band exposures of the plan (spectwin calibrate's), None: the model's."
    )


def _demo(settings: ProgramSettings, fault_rate: float, dry_run: bool):
    from twin.gonio.sim_session import demo_program

    return demo_program(settings.seed, fault_rate=fault_rate), {}


def _calibration(settings: ProgramSettings, fault_rate: float, dry_run: bool):
    from twin.gonio.capture import gonio_calibration_program

    return gonio_calibration_program(seed=settings.seed), {}


def _run(settings: GonioRunSettings, fault_rate: float, dry_run: bool):
    from twin.gonio.capture import SAMPLINGS, gonio_measurement_program
    from twin.gonio.render import GONIO_SPP

    if settings.sampling is None:
        raise InputError(
            "sampling: captured at its own direction pairs, which a resumed capture cannot rebuild"
        )
    notes: dict[str, object] = {}
    exposures_s = settings.exposures_s
    if exposures_s is None:
        if not dry_run:
            raise InputError(
                "calibration: a gonio-run needs the band exposure plan of a gonio calibration"
            )
        from twin.gonio.capture_time import band_exposures_s
        from twin.rigs.rig_config import load_rig

        _, model_exposures_s = band_exposures_s(load_rig("gonio"))
        exposures_s = tuple(float(value) for value in model_exposures_s)
        notes["exposures"] = "the rig model's band plan (no calibration given)"
    built = gonio_measurement_program(
        np.asarray(exposures_s, np.float64),
        material=settings.material,
        rings=SAMPLINGS[settings.sampling],
        pixels=settings.pixels,
        window=settings.window,
        spp=GONIO_SPP if settings.spp is None else settings.spp,
        seed=settings.seed,
    )
    if not dry_run:
        warnings = _registration_warnings(built, settings)
        if warnings:
            notes["warning"] = "; ".join(warnings)
    return built, notes


def _registration_warnings(built: CaptureProgram, settings: GonioRunSettings) -> list[str]:
    """What a run at ``settings`` is predicted to leave unregistered: pairs whose marks the
    window cuts into, pairs whose marks are too narrow at ``--pixels``
    (:mod:`twin.gonio.mark_width`)."""
    from twin.gonio.mark_width import UNLIKELY_BELOW_PX

    warnings = []
    marks = built.marks_outside_window()
    if marks.get("pairs_with_marks_outside_window"):
        warnings.append(
            f"in {marks['pairs_with_marks_outside_window']} of {len(built.poses)} pairs the "
            f"{settings.window} px window cuts into the holder's registration marks, so they may "
            f"not register; a window of {marks['window_px_holding_marks']} px holds them in "
            "every pair"
        )
    outlook = built.registration_outlook()
    if outlook is not None and outlook.unlikely:
        enough = outlook.pixels_registering_every_pair
        remedy = (
            f"--pixels {enough} or more registers every pair"
            if enough is not None
            else "no --pixels the camera takes registers every pair"
        )
        warnings.append(
            f"{len(outlook.unlikely)} of {len(built.poses)} pairs are unlikely to register at "
            f"--pixels {settings.pixels}: their registration marks are under "
            f"{UNLIKELY_BELOW_PX} px wide (narrowest {outlook.narrowest_mark_px:.2f} px); "
            f"{remedy}"
        )
    return warnings


def _stored(capture: CaptureStore) -> dict[str, Any]:
    from twin.gonio.capture import stored_settings

    return stored_settings(capture)


def _stored_seed(capture: CaptureStore) -> ProgramSettings:
    return GonioCalibrationSettings(seed=_stored(capture)["seed"])


def _stored_run(capture: CaptureStore) -> GonioRunSettings:
    stored = _stored(capture)
    return GonioRunSettings(
        seed=stored["seed"],
        material=stored["material"],
        pixels=stored["pixels"],
        window=stored["window"],
        sampling=stored["sampling"],
        spp=stored["spp"],
        exposures_s=tuple(float(value) for value in stored["exposures_s"]),
    )


def _calibrate(
    capture: CaptureStore, out: Path | None, options: dict[str, Any], show_progress: bool
) -> Outcome:
    from recon.calibration.gonio import calibrate_gonio, lamp_rounding_s

    out = GONIO_CALIBRATION if out is None else out
    result = calibrate_gonio(
        capture, white_fill=options.get("white_fill", 0.7), round_to_s=lamp_rounding_s(capture)
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    result.save(out)
    exposures = result.planned_exposure_s
    summary = {
        "calibration": str(out),
        "bands": int(result.bands_nm.size),
        "base_s": result.base_s,
        "planned_exposure_s": exposures.tolist(),
        "exposure_per_pair_s": float(exposures.sum()),
        "all_multiples_of_1_15_s": bool(np.allclose(exposures * 15, np.round(exposures * 15))),
    }
    return Outcome("gonio calibration", summary)


def _process(
    capture: CaptureStore,
    calibration: Path,
    out: Path,
    options: dict[str, Any],
    show_progress: bool,
) -> Outcome:
    from recon.btf.inputs import input_digests
    from recon.btf.processing import check_gonio_run
    from recon.calibration.gonio import GonioCalibration
    from twin.devices.cluster import cluster_description, dask_client, run_process

    gonio_calibration = GonioCalibration.load(calibration)
    check_gonio_run(capture, gonio_calibration)
    digests = input_digests(capture, calibration)
    with dask_client(options.get("workers", 1), options.get("scheduler")) as client:
        cluster = cluster_description(client)
        btf = run_process(
            capture,
            gonio_calibration,
            out,
            texels=options.get("texels"),
            manual_corners=options.get("manual_corners"),
            resume=options.get("resume", False),
            show_progress=show_progress,
            client=client,
            digests=digests,
        )
    found = btf.metadata
    unregistered = list(recorded(found.unregistered_pairs, f"{out}: unregistered_pairs"))
    summary = {
        "btf": str(out),
        "shape": list(btf.shape),
        "complete": btf.complete,
        "coarse_corner_pairs": list(
            recorded(found.coarse_corner_pairs, f"{out}: coarse_corner_pairs")
        ),
        "unregistered_pairs": unregistered,
        "cluster": cluster,
    }
    failure = None
    if unregistered:
        failure = (
            f"{format_pairs(unregistered)} were not registered: give their corners in a manual "
            'corner file (keys "pair<i>")'
        )
    shown = summary | {"unregistered_pairs": format_pairs(unregistered) if unregistered else "none"}
    return Outcome("gonio processing", shown, as_json=summary, failure=failure)


def _evaluate(btf: Path, spp: int, figure: Path | None) -> Outcome:
    from recon.btf.store import BTFStore
    from twin.validate.gonio_evaluation import evaluate_gonio, pair_label, write_gonio_figure
    from twin.validate.gonio_texel_evaluation import GonioTexelEvaluation, write_texel_figure

    result = evaluate_gonio(btf, spp=spp)
    summary = result.summary()
    if figure is not None:
        figure.parent.mkdir(parents=True, exist_ok=True)
        store = BTFStore.open(btf)
        if isinstance(result, GonioTexelEvaluation):
            labels = [pair_label(store, pair) for pair in result.pairs]
            written = write_texel_figure(result, labels, figure)
        else:
            written = write_gonio_figure(result, store, figure)
        summary["figure"] = str(written)
    return Outcome("BTF vs the twin's truth", summary)


def _estimate(config: GonioConfig) -> Outcome:
    from twin.gonio.capture_time import estimate_gonio

    return Outcome(f"capture time: {config.name}", estimate_gonio(config).as_dict())


GONIO = RigKind(
    name=NAME,
    config=GonioConfig,
    programs=(
        ProgramKind("demo", ProgramSettings, _demo, _stored_seed, fault_rate=True),
        ProgramKind("gonio-calibration", GonioCalibrationSettings, _calibration, _stored_seed),
        ProgramKind("gonio-run", GonioRunSettings, _run, _stored_run),
    ),
    calibrate=_calibrate,
    process=_process,
    evaluate=_evaluate,
    estimate=_estimate,
    sweep=SweepKind(GonioConfig, GonioPlan, GONIO_MEASURES, check_gonio_point, measure_gonio_point),
    calibration_file=GONIO_CALIBRATION,
    calibrate_options=frozenset({"white_fill"}),
    process_options=frozenset({"workers", "scheduler"}),
)
"""The spectral gonioreflectometer (``scenes/rigs/gonio.yaml``)."""
