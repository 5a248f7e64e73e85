"""``spectwin lab check LAB`` and ``spectwin lab emulate --out DIR``: a lab's real devices.

``check`` opens every real device of a devices file (:mod:`hwbridge.lab`) and prints who
answered, in how long; it exits 1 naming the first device that did not answer. ``emulate``
serves the rig's serial devices on pseudo-terminals and writes ``DIR/lab.yaml`` pointing at them
(:mod:`hwbridge.emulators.emulated_lab`), until Ctrl-C; then it prints the bytes exchanged with
each device.
"""

from __future__ import annotations

import json
import signal
import threading
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from twin.cli.errors import SpectwinGroup, fail, require_output_folder, run_failed
from twin.cli.output import JsonFlag, console

__all__ = ["register"]

lab_app = typer.Typer(
    cls=SpectwinGroup,
    help="A lab's real devices: check that each answers, or emulate them on the wire.",
    no_args_is_help=True,
)


class Rig(StrEnum):
    dome = "dome"
    gonioreflectometer = "gonioreflectometer"


class Cameras(StrEnum):
    sim = "sim"
    genicam = "genicam"


@lab_app.command()
def check(
    lab: Annotated[Path, typer.Argument(help="The devices file (lab.yaml).")],
    as_json: JsonFlag = False,
) -> None:
    """Open every real device of the devices file, ask it who it is and time the answer; exit
    1 naming the first device that did not answer.

    Example: spectwin lab check lab.yaml
    """
    from hwbridge.lab import load_lab
    from hwbridge.lab_check import check_lab

    devices = load_lab(lab)
    if not devices.wired():
        fail(f"{lab}: every role is sim; expected at least one real device to check")
    if as_json:
        checks = check_lab(devices)
    else:
        with console.status("asking the devices"):
            checks = check_lab(devices)
    if as_json:
        typer.echo(json.dumps([found.as_dict() for found in checks], indent=2))
    else:
        table = Table(title=f"{devices.rig} devices of {lab}")
        for column in ("role", "driver", "address", "model", "serial", "firmware", "state"):
            table.add_column(column)
        table.add_column("round trip", justify="right")
        for found in checks:
            trip = "" if found.round_trip_ms is None else f"{found.round_trip_ms:.1f} ms"
            state = "ok" if found.ok else f"[red]{found.state}[/red]"
            row = (found.role, found.driver, found.address, found.model, found.serial)
            table.add_row(*row, found.firmware, state, trip)
        console.print(table)
    failed = [found for found in checks if not found.ok]
    if failed:
        first = failed[0]
        others = f" (and {len(failed) - 1} more)" if len(failed) > 1 else ""
        run_failed(
            f"{first.role} ({first.driver} on {first.address}) did not answer: {first.state}"
            f"{others}"
        )


def _options(given: list[str]) -> dict[str, dict[str, str]]:
    """``ROLE.KEY=VALUE`` settings, by role."""
    options: dict[str, dict[str, str]] = {}
    for setting in given:
        name, equals, value = setting.partition("=")
        role, dot, key = name.partition(".")
        if not (equals and dot and role and key):
            fail(f"--option {setting!r}: expected ROLE.KEY=VALUE, e.g. stage.speed=360")
        options.setdefault(role, {})[key] = value
    return options


@lab_app.command()
def emulate(
    out: Annotated[Path, typer.Option(help="Folder for lab.yaml.")] = Path("out/lab"),
    rig: Annotated[Rig, typer.Option(help="The rig whose serial devices are emulated.")] = Rig.dome,
    cameras: Annotated[
        Cameras,
        typer.Option(
            help="sim: the twin renders what the devices were told; genicam: the spectral "
            "camera (the gonioreflectometer's camera) is the genicam package's simulated camera."
        ),
    ] = Cameras.sim,
    option: Annotated[
        list[str] | None,
        typer.Option(
            help="An emulator setting ROLE.KEY=VALUE (repeat it): stage.speed (deg/s, default "
            "10), lctf.settle_ms (default 50), and the faults ROLE.silent=1, ROLE.garble=1.",
        ),
    ] = None,
    as_json: JsonFlag = False,
) -> None:
    """Serve the rig's stage, LEDs and LCTF on pseudo-terminals and write OUT/lab.yaml pointing
    at them, until Ctrl-C; then print the bytes exchanged with each.

    Example: spectwin lab emulate --out out/lab, then in another terminal spectwin capture
    dome-calibration out/cal.capture.zarr --devices out/lab/lab.yaml
    """
    from hwbridge.emulators.emulated_lab import EmulatedLab

    require_output_folder(out)
    producer = None
    if cameras is Cameras.genicam:
        from hwbridge.drivers.genicam_camera import simulated_producer

        producer = simulated_producer()
    lab = EmulatedLab(out, rig.value, _options(option or []), producer)
    stop = threading.Event()
    stopping = (signal.SIGINT, signal.SIGTERM)
    previous = {number: signal.signal(number, lambda *_: stop.set()) for number in stopping}
    try:
        with lab as path:
            if not as_json:
                console.print(f"emulating the {rig.value}'s devices; devices file {path}")
                for role, link in lab.traffic().items():
                    console.print(f"  {role}: {link['device']} on {link['port']}")
                console.print("Ctrl-C stops them")
            while not stop.wait(0.2):
                pass
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    traffic = lab.traffic()
    if as_json:
        typer.echo(json.dumps({"lab": str(lab.path), "devices": traffic}, indent=2))
        return
    console.print("stopped; bytes exchanged:")
    for role, link in traffic.items():
        console.print(
            f"  {role} ({link['device']}): {link['bytes_from_host']} from the host, "
            f"{link['bytes_to_host']} to it"
        )


def register(app: typer.Typer) -> None:
    """Add ``lab`` and its commands to ``app``."""
    app.add_typer(lab_app, name="lab")
