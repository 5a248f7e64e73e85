"""``spectwin`` commands of the gonioreflectometer pipeline: capture, calibrate, process, compress,
evaluate, validate.

A full twin run at reduced sampling (thesis 3.3 and 4.1)::

    spectwin capture out/cal.capture.zarr --program gonio-calibration
    spectwin calibrate out/cal.capture.zarr --out out/cal.json
    spectwin capture out/run.capture.zarr --program gonio-run --calibration out/cal.json
    spectwin process out/run.capture.zarr --calibration out/cal.json --out out/cc.btf.zarr
    spectwin compress out/cc.btf.zarr --layout joint
    spectwin evaluate out/cc.btf.zarr --figure out/cc_vs_truth.png
    spectwin validate out/cc.btf.zarr --out out/validation

``calibrate``, ``process`` and ``evaluate`` take the dome's stores too
(:mod:`twin.cli.dome_pipeline`).
"""

from __future__ import annotations

import shlex
from collections import Counter
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any, NoReturn

import numpy as np
import typer

from twin.cli.errors import (
    INTERRUPT_REPORT,
    INTERRUPTED,
    fail,
    require_output_file,
    require_output_folder,
    run_failed,
)
from twin.cli.output import JsonFlag, SchedulerOption, WorkersOption, console, print_summary
from twin.cli.store import require_sound_btf, require_sound_capture

__all__ = ["register"]

SppOption = Annotated[int, typer.Option(min=1, max=65536, help="Samples per pixel of the renders.")]
MAX_FAULT_RATE = 0.1
"""Largest injected fault rate: each device call is retried 3 times, so at 0.1 a fault outlasts
the retries about once in 10^4 calls (the demo session makes about 250); at 0.2 most sessions
stop."""


class Program(StrEnum):
    demo = "demo"
    gonio_calibration = "gonio-calibration"
    gonio_run = "gonio-run"
    dome_calibration = "dome-calibration"
    dome_run = "dome-run"


_DOME = {Program.dome_calibration, Program.dome_run}


class Sampling(StrEnum):
    reduced = "reduced"
    glossy = "glossy"


class LedRenders(StrEnum):
    pose = "pose"
    single = "single"


class Layout(StrEnum):
    per_band = "per_band"
    joint = "joint"


# The capture options that only some programs use (the others refuse them).
_PROGRAM_OPTIONS = {
    "calibration": {Program.gonio_run},
    "material": {Program.gonio_run, Program.dome_run},
    "pixels": {Program.gonio_run},
    "window": {Program.gonio_run},
    "sampling": {Program.gonio_run},
    "spp": {Program.gonio_run, *_DOME},
    "fault_rate": {Program.demo, *_DOME},
    "stage_positions": {Program.dome_run},
    "leds": _DOME,
    "led_renders": _DOME,
    "rgb_cameras": _DOME,
    "texels": _DOME,
    "dark_frames": {Program.dome_calibration},
}
# Options a --dry-run (which captures nothing) refuses.
_CAPTURE_ONLY = ("seed", "resume", "fault_rate", "workers", "scheduler")
# Settings a resumed capture reads from its store (given ones must agree).
_STORED = (
    "program",
    "seed",
    "material",
    "pixels",
    "window",
    "spp",
    "sampling",
    "stage_positions",
    "leds",
    "led_renders",
    "rgb_cameras",
    "texels",
    "dark_frames",
)


def _given(ctx: typer.Context, name: str) -> bool:
    """Whether option ``name`` was given on the command line."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name == "COMMANDLINE"


def _option(ctx: typer.Context, name: str) -> str:
    return next(p.opts[0] for p in ctx.command.params if p.name == name)


def _refuse_unused(ctx: typer.Context, program: Program) -> None:
    for name, programs in _PROGRAM_OPTIONS.items():
        if program not in programs and _given(ctx, name):
            used_by = ", ".join(sorted(p.value for p in programs))
            fail(
                f"{_option(ctx, name)} is not used by --program {program.value} "
                f"(only by {used_by}); leave it out"
            )


def _refuse_capture_only(ctx: typer.Context) -> None:
    for name in _CAPTURE_ONLY:
        if _given(ctx, name):
            fail(f"{_option(ctx, name)} is not used by --dry-run, which captures nothing")


def _shown(name: str, value: object) -> str:
    if name == "window" and value is None:
        return "none (the whole field)"
    return str(value.value if isinstance(value, Program) else value)


def _stored_settings(ctx: typer.Context, store: Path, given: dict[str, object]) -> dict:
    """The program and settings of the capture store to resume; an option given on the command
    line must agree with the store's value."""
    from hwbridge.lock import lock_owner
    from hwbridge.store import CaptureStore
    from twin.dome.programs import stored_dome_settings
    from twin.gonio.capture import stored_settings

    if not store.exists():
        if lock_owner(store) is None:
            fail(f"{store} does not exist: start the capture without --resume")
    else:
        capture = CaptureStore.open(store)
        stored = stored_settings(capture)  # refuses stores spectwin capture did not make
        if str(stored["program"]).startswith("dome-"):
            stored = stored_dome_settings(capture)
        if stored["program"] not in {p.value for p in Program}:
            fail(f"{store}: made by program {stored['program']!r}, which capture does not know")
        stored["program"] = Program(stored["program"])
        if stored["program"] is Program.gonio_run:
            side = given["window"] or given["pixels"]
            if _given(ctx, "window") and side == (stored["window"] or stored["pixels"]):
                given = given | {"window": stored["window"]}  # the whole field, named
        for name in _STORED:
            if name in stored and _given(ctx, name) and given[name] != stored[name]:
                option = _option(ctx, name)
                fail(
                    f"{store} was captured with {option} {_shown(name, stored[name])}, not "
                    f"{_shown(name, given[name])}: leave {option} out to resume it with the "
                    "store's value"
                )
        return stored
    return {}


def _program_of(
    program: Program,
    *,
    calibration: Path | None,
    exposures_s: np.ndarray | None,
    material: str,
    pixels: int,
    window: int | None,
    sampling: Sampling,
    spp: int | None,
    seed: int,
    fault_rate: float,
    dry_run: bool,
    dome: dict[str, Any],
):
    """The capture program, every setting checked (nothing is written)."""
    if program in _DOME:
        from twin.dome.programs import (
            DEFAULT_SPP,
            DomeCaptureSize,
            dome_calibration_program,
            dome_run_program,
        )

        size = DomeCaptureSize(
            dome["stage_positions"],
            dome["leds"],
            dome["rgb_cameras"],
            dome["texels"],
            DEFAULT_SPP if spp is None else spp,
            str(dome["led_renders"]),
        )
        if program is Program.dome_run:
            return dome_run_program(material, size=size, seed=seed, fault_rate=fault_rate), {}
        calibration_program = dome_calibration_program(
            size=size, dark_frames=dome["dark_frames"], seed=seed, fault_rate=fault_rate
        )
        return calibration_program, {}
    if program is Program.demo:
        from twin.gonio.sim_session import demo_program

        return demo_program(seed, fault_rate=fault_rate), {}
    if program is Program.gonio_calibration:
        from twin.gonio.capture import gonio_calibration_program

        return gonio_calibration_program(seed=seed), {}
    from recon.calibration.gonio import GonioCalibration
    from twin.gonio.capture import SAMPLINGS, gonio_measurement_program
    from twin.gonio.render import GONIO_SPP

    if window is not None and window > pixels:
        fail(f"--window {window} is larger than --pixels {pixels}; expected at most {pixels}")
    notes: dict[str, object] = {}
    if calibration is not None:
        planned = GonioCalibration.load(calibration).planned_exposure_s
        if exposures_s is not None and not np.array_equal(planned, exposures_s):
            fail(
                f"--calibration {calibration} plans other band exposures than the store's run "
                "was captured with: leave --calibration out to resume it with the store's"
            )
        exposures_s = planned
    elif exposures_s is None:
        if not dry_run:
            fail("--program gonio-run needs --calibration (the JSON of spectwin calibrate)")
        from twin.gonio.capture_time import band_exposures_s
        from twin.rigs.rig_config import load_rig

        _, exposures_s = band_exposures_s(load_rig("gonio"))
        notes["exposures"] = "the rig model's band plan (no --calibration given)"
    built = gonio_measurement_program(
        exposures_s,
        material=material,
        rings=SAMPLINGS[sampling.value],
        pixels=pixels,
        window=window,
        spp=GONIO_SPP if spp is None else spp,
        seed=seed,
    )
    return built, notes


def _warn_of_marks_outside(built, window: int | None) -> None:
    """One line on stderr when the read-out window cuts into the holder's registration marks
    in some of a measurement run's pairs (they would be captured but may not register)."""
    marks = built.marks_outside_window()
    cut = marks["pairs_with_marks_outside_window"]
    if cut:
        typer.echo(
            f"warning: in {cut} of {len(built.poses)} pairs the {window} px window cuts into "
            "the holder's registration marks, so they may not register; a window of "
            f"{marks['window_px_holding_marks']} px holds them in every pair",
            err=True,
        )


def _interrupted(store: Path, done: int | None = None, total: int | None = None) -> NoReturn:
    """Say how far an interrupted capture got and how to continue it; exit 130."""
    if done is None:
        from hwbridge.store import CaptureStore

        if not store.exists():
            typer.echo("interrupted before the store was created; nothing was written", err=True)
            raise typer.Exit(INTERRUPTED)
        capture = CaptureStore.open(store)
        total = len(capture.attrs["plan"])
        done = total - len(capture.pending_steps())
    then = (
        "the capture is complete"
        if done == total
        else f"continue with: spectwin capture {shlex.quote(str(store))} --resume"
    )
    typer.echo(f"interrupted after {done} of {total} frames; {then}", err=True)
    raise typer.Exit(INTERRUPTED)


def capture(
    ctx: typer.Context,
    store: Annotated[
        Path, typer.Argument(help="Capture store to write, e.g. out/run.capture.zarr.")
    ],
    program: Annotated[
        Program,
        typer.Option(
            help="demo: darks + 2 pairs x 33 bands of the white standard; gonio-calibration: "
            "darks, response series, white standard; gonio-run: a measurement run "
            "(needs --calibration); dome-calibration: the dome's darks, response series, white "
            "standard under the LEDs, checkerboard frames; dome-run: the dome's measurement of "
            "a material (HDR sets and scheduled spectral bands per stage position and LED). "
            "With --resume: the store's."
        ),
    ] = Program.demo,
    calibration: Annotated[
        Path | None,
        typer.Option(
            help="gonio-run: spectwin calibrate's JSON, the band exposure plan (a --dry-run "
            "without it uses the rig model's plan; --resume reads the store's)."
        ),
    ] = None,
    material: Annotated[
        str, typer.Option(help="gonio-run, dome-run: material on the holder (scenes/materials).")
    ] = "colorchecker16",
    pixels: Annotated[
        int,
        typer.Option(
            min=32,
            max=4096,
            help="gonio-run: pixels across the camera's 20 cm field (at most the sensor's).",
        ),
    ] = 256,
    window: Annotated[
        int | None,
        typer.Option(
            min=16,
            max=4096,
            help="gonio-run: read out only the centred window of this many pixels (ROI; at "
            "most --pixels).",
        ),
    ] = None,
    sampling: Annotated[
        Sampling,
        typer.Option(
            help="gonio-run: the direction sampling; reduced: 13 directions (polar 0, 30, 60), "
            "156 pairs; glossy: Sattler's 57 directions up to 60 degrees, 3192 pairs, about "
            "30 min (Figure 4.6 holds on glossy fields)."
        ),
    ] = Sampling.reduced,
    spp: Annotated[
        int | None,
        typer.Option(
            min=1,
            max=65536,
            help="gonio-run, dome programs: samples per pixel of the renders (default 16 "
            "stratified: twin.gonio.render.GONIO_SPP, twin.dome.render.DOME_SPP).",
        ),
    ] = None,
    stage_positions: Annotated[
        int,
        typer.Option(min=1, max=24, help="dome-run: the first stage positions (15 deg steps)."),
    ] = 24,
    leds: Annotated[
        int, typer.Option(min=1, max=198, help="dome programs: LEDs, spread over the dome.")
    ] = 198,
    rgb_cameras: Annotated[
        int,
        typer.Option(min=1, max=11, help="dome programs: RGB cameras, spread over the arc."),
    ] = 11,
    led_renders: Annotated[
        LedRenders,
        typer.Option(
            help="dome programs: pose renders the LEDs of a stage position together, each "
            "camera's paths traced once for all of them; single renders one LED at a time "
            "(slower; other render noise, same physics). With --resume: the store's."
        ),
    ] = LedRenders.pose,
    texels: Annotated[
        int,
        typer.Option(
            min=4,
            max=1024,
            help="dome programs: texels across a 4 cm sample, one Bayer quad each; sets the "
            "frame size (64: 264 x 264 px windows).",
        ),
    ] = 64,
    dark_frames: Annotated[
        int,
        typer.Option(
            min=1,
            max=10000,
            help="dome-calibration: dark frames per exposure time of the spectral camera "
            "(thesis 10.3: 200).",
        ),
    ] = 200,
    seed: Annotated[
        int,
        typer.Option(
            min=0, help="Session seed (noise of every frame). With --resume: the store's."
        ),
    ] = 0,
    resume: Annotated[
        bool,
        typer.Option(
            "--resume",
            help="Continue an interrupted session, with the program and settings in the store.",
        ),
    ] = False,
    dry_run: Annotated[
        bool,
        typer.Option(
            "--dry-run",
            help="Print the plan (steps, frames, estimated duration, storage); write nothing.",
        ),
    ] = False,
    fault_rate: Annotated[
        float,
        typer.Option(
            min=0.0,
            max=MAX_FAULT_RATE,
            help="demo, dome programs: injected device faults per device call (each is retried "
            "3 times).",
        ),
    ] = 0.0,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    as_json: JsonFlag = False,
) -> None:
    """Capture a simulated gonioreflectometer or dome session into a capture store (resumable).

    One writer per store: a second capture, resume or process of the same store is refused
    while the first runs. Ctrl-C (or SIGTERM) stops after the current frame and says how to
    continue; --resume continues with the program and settings the store was made with.

    With --workers N (a local cluster) or --scheduler ADDRESS the steps run as Dask tasks, view
    by view; the frames are bit-identical to a capture in one process.

    Example: spectwin capture out/run.capture.zarr --program gonio-run --calibration cal.json

    A reduced dome capture: spectwin capture out/lego.capture.zarr --program dome-run
    --material lego --stage-positions 2 --leds 24 --rgb-cameras 3 --texels 64
    """
    from hwbridge.errors import SessionInterrupted
    from hwbridge.lock import require_new_store

    ctx.meta[INTERRUPT_REPORT] = lambda: _interrupted(store)  # a Ctrl-C as the command returns
    if dry_run:
        _refuse_capture_only(ctx)
    exposures_s = None
    dome = {
        "stage_positions": stage_positions,
        "leds": leds,
        "rgb_cameras": rgb_cameras,
        "texels": texels,
        "dark_frames": dark_frames,
        "led_renders": led_renders,
    }
    if resume:
        given = {
            "program": program,
            "seed": seed,
            "material": material,
            "pixels": pixels,
            "window": window,
            "sampling": sampling,
            "spp": spp,
            **dome,
        }
        stored = _stored_settings(ctx, store, given)
        program, seed = stored.get("program", program), stored.get("seed", seed)
        if program is Program.gonio_run and stored:
            material, pixels, window = stored["material"], stored["pixels"], stored["window"]
            spp, exposures_s = stored["spp"], stored["exposures_s"]
            if stored["sampling"] is None:
                fail(f"{store}: captured at its own direction pairs, which --resume cannot rebuild")
            sampling = Sampling(stored["sampling"])
        if program in _DOME and stored:
            material, spp = stored.get("material", material), stored["spp"]
            dome = {name: stored.get(name, value) for name, value in dome.items()}
    _refuse_unused(ctx, program)
    if Path(material).suffix:  # a user's material file: the store records where it lies
        material = str(Path(material).resolve())
    built, notes = _program_of(
        program,
        calibration=calibration,
        exposures_s=exposures_s,
        material=material,
        pixels=pixels,
        window=window,
        sampling=sampling,
        spp=spp,
        seed=seed,
        fault_rate=fault_rate,
        dry_run=dry_run,
        dome=dome,
    )
    summary: dict[str, object] = {"store": str(store)}
    if dry_run:
        summary |= built.dry_run() | notes | {"written": "nothing (dry run)"}
        print_summary(summary, "capture (dry run)", as_json)
        return
    if not resume:
        require_new_store(store)
    require_output_folder(store, "STORE")
    if program is Program.gonio_run:
        _warn_of_marks_outside(built, window)
    from twin.devices.cluster import cluster_description, dask_client

    summary["program"] = program.value
    try:
        with dask_client(workers, scheduler) as client:
            summary["cluster"] = cluster_description(client)
            result = built.run(store, resume=resume, show_progress=not as_json, client=client)
        cameras = dict.fromkeys(step["camera"] for step in result.attrs["plan"])
        indexes = [result.index(camera, ["kind", "status"]) for camera in cameras]
        recaptured = [
            f"{problem.item}: {problem.key} was {problem.problem}" for problem in result.recaptured
        ]
        summary |= {
            "complete": result.complete,
            "frames": dict(sum((Counter(index["kind"].tolist()) for index in indexes), Counter())),
            "frames_with_faults": int(
                sum(status != "ok" for index in indexes for status in index["status"])
            ),
            "recaptured_frames": len(recaptured),
        }
        if as_json:
            summary["recaptured"] = recaptured
        for line in recaptured:
            typer.echo(f"re-captured {line}")
        print_summary(summary, "capture (simulated backend)", as_json)
    except SessionInterrupted as stop:
        _interrupted(store, stop.done, stop.total)
    except KeyboardInterrupt:  # outside the session's own handling (the summary), or a second one
        _interrupted(store)


def _is_dome(capture) -> bool:
    """Whether a capture store holds a dome capture (its ``rig["rig"]``)."""
    return (capture.attrs.get("rig") or {}).get("rig") == "dome"


def calibrate(
    ctx: typer.Context,
    store: Annotated[
        Path, typer.Argument(help="A gonio-calibration or dome-calibration capture store.")
    ],
    out: Annotated[
        Path | None,
        typer.Option(
            help="Calibration to write: JSON for the gonioreflectometer (default cal.json), "
            ".npz for the dome (default dome_cal.npz)."
        ),
    ] = None,
    white_fill: Annotated[
        float,
        typer.Option(
            min=0.01,
            max=0.99,
            help="gonio: fraction of the range the white standard should reach.",
        ),
    ] = 0.7,
    as_json: JsonFlag = False,
) -> None:
    """Gonioreflectometer: response curve (Robertson), white factors F' (Eq. 3.3) and the
    exposure plan (Eq. 3.4, multiples of 1/15 s for the HMI lamp). Dome: every camera's
    geometry (checkerboard frames, OpenCV), the spectral camera's low-SNR calibration (10.3),
    the RGB cameras' responses and the white standard under every LED.

    Example: spectwin calibrate out/cal.capture.zarr --out out/cal.json
    """
    from hwbridge.store import CaptureStore
    from recon.calibration.gonio import calibrate_gonio, lamp_rounding_s

    capture = CaptureStore.open(store)
    if _is_dome(capture):
        from twin.cli.dome_pipeline import calibrate_dome_store

        if _given(ctx, "white_fill"):
            fail("--white-fill is not used by a dome calibration; leave it out")
        calibrate_dome_store(capture, store, out, as_json)
        return
    out = Path("cal.json") if out is None else out
    require_output_file(out)
    require_sound_capture(capture, store)
    with console.status("calibrating"):
        result = calibrate_gonio(
            capture, white_fill=white_fill, round_to_s=lamp_rounding_s(capture)
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
    print_summary(summary, "gonio calibration", as_json)


def process(
    ctx: typer.Context,
    store: Annotated[Path, typer.Argument(help="A gonio-run or dome-run capture store.")],
    calibration: Annotated[
        Path, typer.Option(help="spectwin calibrate's JSON (gonio) or .npz (dome).")
    ],
    out: Annotated[Path, typer.Option(help="BTF store to write (<name>.btf.zarr).")],
    texels: Annotated[
        int | None,
        typer.Option(
            min=16,
            max=1024,
            help="Texture resolution per side (at least 16: evaluate and validate need texels "
            "inside every chart field). Default: 128 (gonio), the capture's texels (dome).",
        ),
    ] = None,
    manual_corners: Annotated[
        Path | None, typer.Option(help="Manual corner file for frames detection misses.")
    ] = None,
    resume: Annotated[
        bool, typer.Option("--resume", help="Continue an interrupted process.")
    ] = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    as_json: JsonFlag = False,
) -> None:
    """Calibrate and register a measurement run into a spectral BTF store: the
    gonioreflectometer's (Eq. 3.6, 4.1.2), or the dome's, spectralized from its RGB images and
    noisy bands (Eq. 10.12, jointly over each cycle of the band schedule, 10.4.2).

    With --workers N (a local cluster) or --scheduler ADDRESS the gonioreflectometer's direction
    pairs are Dask tasks; the BTF is the same as from one process.

    Example: spectwin process out/run.capture.zarr --calibration out/cal.json --out out/cc.btf.zarr
    """
    from hwbridge.lock import require_new_store, require_no_writer
    from hwbridge.store import CaptureStore
    from recon.btf.processing import check_gonio_run
    from recon.calibration.gonio import GonioCalibration
    from recon.registration.border import read_manual_corners
    from twin.devices.cluster import cluster_description, dask_client, run_process

    # Everything that can be checked is, before the first frame is read: the options, the
    # calibration, the output, the store's integrity and progress, its kind and bands.
    if out.resolve() == store.resolve():
        fail(f"--out {out} is the capture store itself; choose another --out")
    require_no_writer(out)
    if not resume:
        require_new_store(out)
    capture = CaptureStore.open(store)
    if _is_dome(capture):
        from twin.cli.dome_pipeline import process_dome_store

        for name in ("workers", "scheduler"):
            if _given(ctx, name):
                fail(f"{_option(ctx, name)} is not used for a dome run; leave it out")
        process_dome_store(
            capture,
            store,
            calibration,
            out,
            texels=texels,
            manual_corners=manual_corners,
            resume=resume,
            as_json=as_json,
        )
        return
    texels = 128 if texels is None else texels
    gonio_calibration = GonioCalibration.load(calibration)
    corners = read_manual_corners(manual_corners) if manual_corners else None
    require_output_folder(out)
    require_sound_capture(capture, store)
    check_gonio_run(capture, gonio_calibration)
    try:
        with dask_client(workers, scheduler) as client:
            cluster = cluster_description(client)
            btf = run_process(
                capture,
                gonio_calibration,
                out,
                texels=texels,
                manual_corners=corners,
                resume=resume,
                show_progress=not as_json,
                client=client,
            )
    except KeyboardInterrupt:
        again = shlex.join(
            ["spectwin", "process", str(store), "--calibration", str(calibration)]
            + ["--out", str(out), "--texels", str(texels), "--resume"]
        )
        typer.echo(f"interrupted; continue with: {again}", err=True)
        raise typer.Exit(INTERRUPTED) from None
    summary = {
        "btf": str(out),
        "shape": list(btf.shape),
        "complete": btf.complete,
        "coarse_corner_pairs": btf.attrs["coarse_corner_pairs"],
        "unregistered_pairs": btf.attrs["unregistered_pairs"],
        "cluster": cluster,
    }
    print_summary(summary, "gonio processing", as_json)
    if summary["unregistered_pairs"]:
        run_failed(
            f"pairs {summary['unregistered_pairs']} were not registered: give their corners in "
            'a manual corner file (keys "pair<i>") and run again with --manual-corners FILE '
            "--resume"
        )


def compress(
    btf: Annotated[Path, typer.Argument(help="A complete BTF store (spectwin process).")],
    brightness: Annotated[
        int, typer.Option(min=1, max=100000, help="PCA components of the brightness.")
    ] = 250,
    spectral: Annotated[
        int,
        typer.Option(
            min=1,
            max=100000,
            help="PCA components of the normalized spectra (per band or joint).",
        ),
    ] = 60,
    layout: Annotated[
        Layout,
        typer.Option(
            help="per_band: one PCA per band (the thesis); joint: one PCA over all bands."
        ),
    ] = Layout.per_band,
    as_json: JsonFlag = False,
) -> None:
    """Compress a BTF by PCA of brightness and normalized spectra (thesis 4.1.2: 250 and 60
    components) into the store's pca/ group; report size and Eq. 6.8 error against the store.

    Example: spectwin compress out/cc.btf.zarr --layout joint --json
    """
    from hwbridge.lock import StoreLock, require_no_writer
    from recon.btf.compression import compress_btf, compression_report, save_compressed
    from recon.btf.store import BTFStore

    require_no_writer(btf)
    require_sound_btf(btf, "compress")
    store = BTFStore.open(btf, writable=True)
    with StoreLock.acquire(btf), console.status("compressing"):
        reflectance = store.read()
        compressed = compress_btf(
            reflectance,
            store.grid,
            n_brightness=brightness,
            n_spectral=spectral,
            layout=layout.value,
        )
        save_compressed(store, compressed)
        report = compression_report(compressed, reflectance)
    print_summary({"btf": str(btf), **report.as_dict()}, "BTF compression", as_json)


def evaluate(
    btf: Annotated[Path, typer.Argument(help="A BTF store made by spectwin process.")],
    figure: Annotated[Path | None, typer.Option(help="PNG of errors and spectra.")] = None,
    spp: Annotated[
        int, typer.Option(min=1, max=65536, help="Samples per pixel of the truth renders.")
    ] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Compare a processed BTF with the twin's true BTF: per-field Eq. 6.8 and corner errors
    (a material without chart fields: per texel, Eq. 6.8 and Delta E94); for a dome BTF also
    Delta E94 (diffuse fields, or the material's texels) and the texture's
    shift against the truth.

    Example: spectwin evaluate out/cc.btf.zarr --figure out/cc_vs_truth.png --json
    """
    from recon.btf.store import BTFStore
    from twin.validate.dome_evaluation import DomeEvaluation, evaluate_dome, write_dome_figure
    from twin.validate.gonio_evaluation import evaluate_gonio, pair_label, write_gonio_figure
    from twin.validate.gonio_texel_evaluation import GonioTexelEvaluation, write_texel_figure

    require_sound_btf(btf, "evaluate", allow_unregistered=True)
    if figure is not None:
        require_output_file(figure, "--figure")
    dome = "dome_pairs" in BTFStore.open(btf).attrs
    with console.status("rendering the truth and comparing"):
        result = evaluate_dome(btf, spp=spp) if dome else evaluate_gonio(btf, spp=spp)
    summary = result.summary()
    if figure is not None:
        figure.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(result, DomeEvaluation):
            written = write_dome_figure(result, figure)
        elif isinstance(result, GonioTexelEvaluation):
            store = BTFStore.open(btf)
            labels = [pair_label(store, pair) for pair in result.pairs]
            written = write_texel_figure(result, labels, figure)
        else:
            written = write_gonio_figure(result, BTFStore.open(btf), figure)
        summary["figure"] = str(written)
    title = "dome BTF vs the twin's truth" if dome else "BTF vs the twin's truth"
    print_summary(summary, title, as_json)


def validate(
    btf: Annotated[Path, typer.Argument(help="A BTF store of the twin's colour checker.")],
    out: Annotated[Path, typer.Option(help="Folder for the PNGs and metrics.json.")] = Path(
        "validation"
    ),
    compressed: Annotated[
        bool, typer.Option("--compressed", help="Render the store's PCA form (spectwin compress).")
    ] = False,
    pixels: Annotated[
        int,
        typer.Option(
            min=23,
            max=2048,
            help="Image size of the three panels (at least 23: every chart field keeps an "
            "interior pixel).",
        ),
    ] = 96,
    spp: Annotated[
        int,
        typer.Option(
            min=4, max=65536, help="Samples per pixel (the photograph's noise adds to Delta E)."
        ),
    ] = 256,
    map_height: Annotated[
        int,
        typer.Option(
            min=4, max=2048, help="Rows of the captured environment map (2x as many columns)."
        ),
    ] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Render the BTF back (thesis 4.2): Figure 4.6 (photograph, spectral and RGB renderings,
    Delta E94 maps) and the 45/0 spectrophotometer comparison, with a metrics JSON.

    Example: spectwin validate out/cc.btf.zarr --out out/validation --compressed
    """
    from twin.validate.render_back import validate_btf

    require_output_folder(out)
    require_sound_btf(btf, "validate", allow_unregistered=True, compressed=compressed)
    with console.status("validating") as status:
        metrics = validate_btf(
            btf,
            out,
            compressed=compressed,
            pixels=pixels,
            spp=spp,
            map_height=map_height,
            step=lambda name: status.update(name),
        )
    if as_json:
        print_summary(metrics, "", as_json)
        return
    figure46, forty_five = metrics["figure46"], metrics["spectrophotometer_45_0"]
    summary = {
        "out": str(out),
        "form": metrics["form"],
        "measured_as": metrics["measured_as"],
        "field_mean_delta_e94_spectral": figure46["field_mean_delta_e94_spectral"],
        "field_mean_delta_e94_rgb": figure46["field_mean_delta_e94_rgb"],
        "field_ratio_rgb_over_spectral": figure46["field_ratio_rgb_over_spectral"],
        "mean_delta_e94_spectral": figure46["mean_delta_e94_spectral"],
        "mean_delta_e94_rgb": figure46["mean_delta_e94_rgb"],
        "45/0_mean_error_matte_fields_pct": forty_five["mean_error_matte_fields_pct"],
        "45/0_max_error_matte_fields_pct": forty_five["max_error_matte_fields_pct"],
    }
    print_summary(summary, "BTF rendered back (Figure 4.6, 45/0)")


def register(app: typer.Typer) -> None:
    """Add the commands to ``app``."""
    for command in (capture, calibrate, process, compress, evaluate, validate):
        app.command()(command)
