"""``spectwin capture PROGRAM STORE``: a simulated capture session into a capture store, one
subcommand per capture program with only its options, and ``spectwin capture resume STORE``.

A full twin run at reduced sampling (thesis 3.3 and 4.1)::

    spectwin capture gonio-calibration out/cal.capture.zarr
    spectwin calibrate out/cal.capture.zarr --out out/cal.json
    spectwin capture gonio-run out/run.capture.zarr --calibration out/cal.json
    spectwin capture resume out/run.capture.zarr

Each program's settings are one frozen model (:mod:`twin.kinds.gonio`, :mod:`twin.kinds.dome`);
a resumed capture takes them from its store, so that it continues the same program.
"""

from __future__ import annotations

import shlex
from collections import Counter
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer
from typer.core import TyperGroup

from hwbridge.errors import Remedy
from twin.cli.errors import (
    INTERRUPT_REPORT,
    INTERRUPTED,
    SpectwinGroup,
    fail,
    require_output_folder,
    run_failed,
)
from twin.cli.given import given, option_name
from twin.cli.output import JsonFlag, SchedulerOption, WorkersOption, print_summary

if TYPE_CHECKING:
    from hwbridge.lab import Lab
    from twin.kinds.kind import ProgramSettings

__all__ = ["capture_app", "register"]

MAX_FAULT_RATE = 0.1
"""Largest injected fault rate: each device call is retried 3 times, so at 0.1 a fault outlasts
the retries about once in 10^4 calls (the demo session makes about 250); at 0.2 most sessions
stop."""


CAPTURE_STORE = "spectwin.capture_store"
"""Key in ``ctx.meta`` of the store a capture command writes, for the advice of its errors."""

CAPTURE_DEVICES = "spectwin.capture_devices"
"""Key in ``ctx.meta`` of the devices file of a capture, for the advice to resume it."""


def resume_command(store: Path, devices: Path | None) -> str:
    """The command that continues the capture into ``store`` on the devices of ``devices``."""
    again = f"spectwin capture resume {shlex.quote(str(store))}"
    return again if devices is None else f"{again} --devices {shlex.quote(str(devices))}"


class CaptureGroup(SpectwinGroup):
    """``spectwin capture``: a program first; a store path in its place (the form without
    programs) gets one line saying so. Errors that a resume mends advise ``spectwin capture
    resume STORE``."""

    def advice(self, ctx: Any, remedy: Remedy | None) -> str | None:
        store = ctx.meta.get(CAPTURE_STORE)
        if store is not None and remedy in (Remedy.resume, Remedy.resume_or_rename):
            again = resume_command(store, ctx.meta.get(CAPTURE_DEVICES))
            if remedy is Remedy.resume:
                return f"continue with {again}"
            return f"continue it with {again} or choose another name"
        return super().advice(ctx, remedy)

    def resolve_command(self, ctx: Any, args: list[str]) -> Any:
        if args and args[0] not in self.commands and not args[0].startswith("-"):
            programs = ", ".join(name for name in self.commands if name != "resume")
            fail(
                f"capture: {args[0]!r} is not a capture program; expected one of {programs} or "
                f"resume, then the store (e.g. spectwin capture dome-run {args[0]})"
            )
        return TyperGroup.resolve_command(self, ctx, args)


capture_app = typer.Typer(
    cls=CaptureGroup,
    help="Capture a gonioreflectometer or dome session into a capture store (resumable): one "
    "program per subcommand, on the twin's devices or, with --devices lab.yaml, on a lab's "
    "(the twin's cameras render what the real stage, LEDs and LCTF were told).\n\n"
    "One writer per store: a second capture, resume or process of the same store is refused "
    "while the first runs. Ctrl-C (or SIGTERM) stops after the current frame and says how to "
    "continue.\n\n"
    "With --workers N (a local cluster) or --scheduler ADDRESS the steps run as Dask tasks, "
    "view by view; the frames are bit-identical to a capture in one process.",
    no_args_is_help=True,
)

StoreArgument = Annotated[
    Path, typer.Argument(help="Capture store to write, e.g. out/run.capture.zarr.")
]
SeedOption = Annotated[int, typer.Option(min=0, help="Session seed (noise of every frame).")]
DryRunFlag = Annotated[
    bool,
    typer.Option(
        "--dry-run",
        help="Print the plan (steps, frames, estimated duration, storage); write nothing.",
    ),
]
FaultRateOption = Annotated[
    float,
    typer.Option(
        min=0.0,
        max=MAX_FAULT_RATE,
        help="Injected device faults per device call (each is retried 3 times).",
    ),
]
SppOption = Annotated[
    int | None,
    typer.Option(
        min=1,
        max=65536,
        help="Samples per pixel of the renders (default: the rig's own, 16 stratified on "
        "both rigs).",
    ),
]
MaterialOption = Annotated[
    str, typer.Option(help="Material on the holder (scenes/materials, or a material file).")
]
LedsOption = Annotated[int, typer.Option(min=1, max=198, help="LEDs, spread over the dome.")]
RgbCamerasOption = Annotated[
    int, typer.Option(min=1, max=11, help="RGB cameras, spread over the arc.")
]
TexelsOption = Annotated[
    int,
    typer.Option(
        min=4,
        max=1024,
        help="Texels across a 4 cm sample, one Bayer quad each; sets the frame size (64: "
        "264 x 264 px windows).",
    ),
]


DevicesOption = Annotated[
    Path | None,
    typer.Option(
        "--devices",
        help="A devices file (lab.yaml, see scenes/labs): its real devices fill the roles it "
        "names, the twin's the roles it leaves sim.",
    ),
]


class LedRenders(StrEnum):
    pose = "pose"
    single = "single"


class Sampling(StrEnum):
    reduced = "reduced"
    glossy = "glossy"


LedRendersOption = Annotated[
    LedRenders,
    typer.Option(
        help="pose renders the LEDs of a stage position together, each camera's paths traced "
        "once for all of them; single renders one LED at a time (slower; other render noise, "
        "same physics).",
    ),
]

# Options a --dry-run (which captures nothing) refuses.
_CAPTURE_ONLY = ("seed", "fault_rate", "workers", "scheduler")


def _material(material: str) -> str:
    """A user's material file by its absolute path (the store records where it lies)."""
    return str(Path(material).resolve()) if Path(material).suffix else material


def _interrupted(
    store: Path,
    devices: Path | None,
    done: int | None = None,
    total: int | None = None,
) -> NoReturn:
    """Say how far an interrupted capture (on the devices of ``devices``) got and how to
    continue it; exit 130."""
    if done is None:
        from hwbridge.store import CaptureStore

        if not store.exists():
            typer.echo("interrupted before the store was created; nothing was written", err=True)
            raise typer.Exit(INTERRUPTED)
        capture = CaptureStore.open(store)
        total = len(capture.metadata.plan)
        done = total - len(capture.pending_steps())
    then = (
        "the capture is complete"
        if done == total
        else f"continue with: {resume_command(store, devices)}"
    )
    typer.echo(f"interrupted after {done} of {total} frames; {then}", err=True)
    raise typer.Exit(INTERRUPTED)


@dataclass(frozen=True)
class Session:
    """How a capture runs, beside what it captures: injected faults, a dry run or a resume,
    where (Dask workers or a scheduler), what it prints and the lab's devices file."""

    fault_rate: float = 0.0
    dry_run: bool = False
    resume: bool = False
    workers: int = 1
    scheduler: str | None = None
    as_json: bool = False
    devices: Path | None = None


def _capture(
    ctx: typer.Context,
    store: Path,
    names: tuple[str, str],
    settings: dict[str, Any] | ProgramSettings,
    session: Session,
) -> None:
    """Build the program ``names`` (the rig's name and the program's) from its settings (every
    one checked, nothing written), then print its dry run or capture it as ``session`` says."""
    rig, program_name = names
    fault_rate, dry_run, resume = session.fault_rate, session.dry_run, session.resume
    workers, scheduler, as_json = session.workers, session.scheduler, session.as_json
    from pydantic import ValidationError

    from hwbridge.errors import SessionInterrupted
    from hwbridge.lock import require_new_store
    from twin.kinds.registry import ProgramSettings, rig_kind

    devices = session.devices
    # a Ctrl-C as the command returns
    ctx.meta[INTERRUPT_REPORT] = lambda: _interrupted(store, devices)
    ctx.meta[CAPTURE_STORE], ctx.meta[CAPTURE_DEVICES] = store, devices
    program = rig_kind(rig).program(program_name)
    if dry_run:
        for name in _CAPTURE_ONLY:
            if given(ctx, name):
                fail(f"{option_name(ctx, name)} is not used by --dry-run, which captures nothing")
    lab = None if devices is None or dry_run else _lab(ctx, devices, rig, program_name)
    if isinstance(settings, ProgramSettings):
        model = settings
    else:
        try:
            model = program.settings(**settings)
        except ValidationError as error:
            first = error.errors()[0]
            fail(f"{'.'.join(map(str, first['loc']))}: {first['msg']}")
    built, notes = program.build(model, fault_rate, dry_run)
    summary: dict[str, object] = {"store": str(store)}
    if dry_run:
        notes.pop("warning", None)
        summary |= built.dry_run() | notes | {"written": "nothing (dry run)"}
        print_summary(summary, "capture (dry run)", as_json)
        return
    require_output_folder(store, "STORE")
    if not resume:
        require_new_store(store)
    if "warning" in notes:
        typer.echo(f"warning: {notes['warning']}", err=True)
    from twin.devices.cluster import cluster_description, dask_client

    summary["program"] = program.name
    try:
        if lab is not None:
            wired = lab.wired().items()
            summary["devices"] = {role: f"{e.driver} on {e.address}" for role, e in wired}
            result = built.run(store, resume=resume, show_progress=not as_json, lab=lab)
        else:
            with dask_client(workers, scheduler) as client:
                summary["cluster"] = cluster_description(client)
                result = built.run(store, resume=resume, show_progress=not as_json, client=client)
        cameras = dict.fromkeys(step.camera for step in result.metadata.plan)
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
        backend = "simulated backend" if lab is None else f"devices of {devices}"
        print_summary(summary, f"capture ({backend})", as_json)
    except SessionInterrupted as stop:
        _interrupted(store, devices, stop.done, stop.total)
    except KeyboardInterrupt:  # outside the session's own handling (the summary), or a second one
        _interrupted(store, devices)


def _lab(ctx: typer.Context, devices: Path, rig: str, program: str) -> Lab:
    """The devices file ``devices``, for ``program`` of ``rig`` (refusing what a lab's
    devices cannot do: injected faults, a cluster)."""
    from hwbridge.lab import load_lab

    for name in ("fault_rate", "workers", "scheduler"):
        if given(ctx, name):
            fail(
                f"{option_name(ctx, name)} is not used with --devices: a lab's devices fail on "
                "their own and are driven from this process"
            )
    lab = load_lab(devices)
    if lab.rig != rig:
        fail(
            f"--devices {devices}: is a devices file of the {lab.rig}; {program} runs on the {rig}"
        )
    return lab


@capture_app.command()
def demo(
    ctx: typer.Context,
    store: StoreArgument,
    seed: SeedOption = 0,
    fault_rate: FaultRateOption = 0.0,
    dry_run: DryRunFlag = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    as_json: JsonFlag = False,
) -> None:
    """Darks and 2 pairs x 33 bands of the white standard on the gonioreflectometer.

    Example: spectwin capture demo out/demo.capture.zarr
    """
    program = ("gonioreflectometer", "demo")
    _capture(
        ctx,
        store,
        program,
        {"seed": seed},
        Session(fault_rate, dry_run, False, workers, scheduler, as_json),
    )


@capture_app.command("gonio-calibration")
def gonio_calibration(
    ctx: typer.Context,
    store: StoreArgument,
    seed: SeedOption = 0,
    dry_run: DryRunFlag = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    devices: DevicesOption = None,
    as_json: JsonFlag = False,
) -> None:
    """The gonioreflectometer's calibration: darks, response series, white standard.

    Example: spectwin capture gonio-calibration out/cal.capture.zarr
    """
    program = ("gonioreflectometer", "gonio-calibration")
    _capture(
        ctx,
        store,
        program,
        {"seed": seed},
        Session(0.0, dry_run, False, workers, scheduler, as_json, devices),
    )


@capture_app.command("gonio-run")
def gonio_run(
    ctx: typer.Context,
    store: StoreArgument,
    calibration: Annotated[
        Path | None,
        typer.Option(
            help="spectwin calibrate's JSON, the band exposure plan (a --dry-run without it "
            "uses the rig model's plan)."
        ),
    ] = None,
    material: MaterialOption = "colorchecker16",
    pixels: Annotated[
        int,
        typer.Option(
            min=32, max=4096, help="Pixels across the camera's 20 cm field (at most the sensor's)."
        ),
    ] = 256,
    window: Annotated[
        int | None,
        typer.Option(
            min=16,
            max=4096,
            help="Read out only the centred window of this many pixels (ROI; at most --pixels).",
        ),
    ] = None,
    sampling: Annotated[
        Sampling,
        typer.Option(
            help="The direction sampling; reduced: 13 directions (polar 0, 30, 60), 156 pairs; "
            "glossy: Sattler's 57 directions up to 60 degrees, 3192 pairs, about 30 min "
            "(Figure 4.6 holds on glossy fields).",
        ),
    ] = Sampling.reduced,
    spp: SppOption = None,
    seed: SeedOption = 0,
    dry_run: DryRunFlag = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    devices: DevicesOption = None,
    as_json: JsonFlag = False,
) -> None:
    """A measurement run of the gonioreflectometer: every direction pair in every band of the
    calibration's exposure plan.

    Example: spectwin capture gonio-run out/run.capture.zarr --calibration out/cal.json
    """
    exposures_s = None
    if calibration is not None:
        from recon.calibration.gonio import GonioCalibration

        planned = GonioCalibration.load(calibration).planned_exposure_s
        exposures_s = tuple(float(value) for value in planned)
    elif not dry_run:
        fail("gonio-run needs --calibration (the JSON of spectwin calibrate)")
    if window is not None and window > pixels:
        fail(f"--window {window} is larger than --pixels {pixels}; expected at most {pixels}")
    settings = {
        "seed": seed,
        "material": _material(material),
        "pixels": pixels,
        "window": window,
        "sampling": sampling.value,
        "spp": spp,
        "exposures_s": exposures_s,
    }
    program = ("gonioreflectometer", "gonio-run")
    _capture(
        ctx,
        store,
        program,
        settings,
        Session(0.0, dry_run, False, workers, scheduler, as_json, devices),
    )


@capture_app.command("dome-calibration")
def dome_calibration(
    ctx: typer.Context,
    store: StoreArgument,
    leds: LedsOption = 198,
    rgb_cameras: RgbCamerasOption = 11,
    texels: TexelsOption = 64,
    dark_frames: Annotated[
        int,
        typer.Option(
            min=1,
            max=10000,
            help="Dark frames per exposure time of the spectral camera (thesis 10.3: 200).",
        ),
    ] = 200,
    spp: SppOption = None,
    led_renders: LedRendersOption = LedRenders.pose,
    seed: SeedOption = 0,
    fault_rate: FaultRateOption = 0.0,
    dry_run: DryRunFlag = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    devices: DevicesOption = None,
    as_json: JsonFlag = False,
) -> None:
    """The dome's calibration: darks, response series, white standard under the LEDs,
    checkerboard frames. The run it calibrates must share its LEDs, RGB cameras and texels.

    Example: spectwin capture dome-calibration out/cal.capture.zarr --leds 24 --rgb-cameras 3
    """
    settings = {
        "seed": seed,
        "leds": leds,
        "rgb_cameras": rgb_cameras,
        "texels": texels,
        "dark_frames": dark_frames,
        "spp": spp,
        "led_renders": led_renders.value,
    }
    program = ("dome", "dome-calibration")
    _capture(
        ctx,
        store,
        program,
        settings,
        Session(fault_rate, dry_run, False, workers, scheduler, as_json, devices),
    )


@capture_app.command("dome-run")
def dome_run(
    ctx: typer.Context,
    store: StoreArgument,
    material: MaterialOption = "colorchecker16",
    stage_positions: Annotated[
        int, typer.Option(min=1, max=24, help="The first stage positions (15 deg steps).")
    ] = 24,
    leds: LedsOption = 198,
    rgb_cameras: RgbCamerasOption = 11,
    texels: TexelsOption = 64,
    spp: SppOption = None,
    led_renders: LedRendersOption = LedRenders.pose,
    seed: SeedOption = 0,
    fault_rate: FaultRateOption = 0.0,
    dry_run: DryRunFlag = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    devices: DevicesOption = None,
    as_json: JsonFlag = False,
) -> None:
    """The dome's measurement of a material: HDR sets and scheduled spectral bands per stage
    position and LED.

    Example: spectwin capture dome-run out/lego.capture.zarr --material lego --stage-positions 2
    --leds 24 --rgb-cameras 3
    """
    settings = {
        "seed": seed,
        "material": _material(material),
        "stage_positions": stage_positions,
        "leds": leds,
        "rgb_cameras": rgb_cameras,
        "texels": texels,
        "spp": spp,
        "led_renders": led_renders.value,
    }
    program = ("dome", "dome-run")
    _capture(
        ctx,
        store,
        program,
        settings,
        Session(fault_rate, dry_run, False, workers, scheduler, as_json, devices),
    )


@capture_app.command()
def resume(
    ctx: typer.Context,
    store: Annotated[Path, typer.Argument(help="The capture store to continue.")],
    fault_rate: FaultRateOption = 0.0,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    devices: DevicesOption = None,
    as_json: JsonFlag = False,
) -> None:
    """Continue an interrupted capture with the program and settings recorded in its store
    (damaged frames are captured again).

    Example: spectwin capture resume out/run.capture.zarr (a capture on a lab's devices: with
    --devices lab.yaml)
    """
    from hwbridge.lock import lock_owner, require_no_writer
    from hwbridge.store import CaptureStore
    from twin.kinds.registry import capture_program

    ctx.meta[CAPTURE_STORE] = store
    require_no_writer(store)  # a store another writer holds is refused before it is read
    if not store.exists():
        if lock_owner(store) is None:
            fail(f"{store} does not exist: start the capture with spectwin capture PROGRAM")
        run_failed(f"{store} is being created by another capture; wait for it to finish")
    capture = CaptureStore.open(store)
    kind, program = capture_program(capture)
    if given(ctx, "fault_rate") and not program.fault_rate:
        fail(f"--fault-rate is not used by {program.name}; leave it out")
    on_a_lab = capture.metadata.backend == "real"
    if on_a_lab and devices is None:
        fail(f"{store} was captured on a lab's devices; resume it with --devices LAB.yaml")
    if not on_a_lab and devices is not None:
        fail(f"{store} was captured on the twin's devices; resume it without --devices")
    session = Session(fault_rate, False, True, workers, scheduler, as_json, devices)
    _capture(ctx, store, (kind.name, program.name), program.stored(capture), session)


def register(app: typer.Typer) -> None:
    """Add ``capture`` and its programs to ``app``."""
    app.add_typer(capture_app, name="capture")
