"""``spectwin store check``: is a capture or BTF store whole? And the refusals of damaged or
incomplete input stores that the gonioreflectometer commands share.

A store is damaged when a unit of work it flags done (a capture step, a BTF direction pair) has a
chunk that is missing, corrupt or sealed elsewhere (swapped, moved, from another store or of
another shape), when it says it is complete while progress flags are unset, when its metadata (a
``zarr.json``) is missing or unreadable, or when the settings that define it or its arrays'
shapes differ from those it was created with (:mod:`hwbridge.integrity`). An
incomplete store (a capture or processing cut short) is not damaged: it resumes.

Exit codes: ``store check`` 0 for a healthy store, 1 for a damaged one. The commands that read a
store refuse a damaged one with exit 1 and an incomplete one with exit 2, in one line that names
the first bad frame or pair, before they read any frame.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Annotated, Any

import typer

from twin.cli.errors import SpectwinGroup, fail, run_failed
from twin.cli.output import JsonFlag, print_summary

__all__ = ["register", "require_sound_btf", "require_sound_capture"]

store_app = typer.Typer(
    cls=SpectwinGroup,
    help="Check capture and BTF stores for missing or corrupt chunks and lost progress flags.",
    no_args_is_help=True,
)


def _kind(path: Path) -> str:
    """``"capture"`` or ``"BTF"``, from the root attributes (or, when the root metadata is
    gone, from the arrays; the stores' ``open`` then names what is missing)."""
    from recon.btf.store import BTF_FORMAT

    if not path.exists():
        fail(f"{path} does not exist: expected a capture store or a BTF store")
    if not path.is_dir():
        fail(f"{path} is a file: expected a capture store or a BTF store (a folder)")
    root = path / "zarr.json"
    if root.is_file():
        try:
            attributes = json.loads(root.read_text()).get("attributes", {})
        except (OSError, UnicodeDecodeError, ValueError, AttributeError) as error:
            run_failed(f"damaged store: {root} is unreadable ({error})")
        if attributes.get("format") == BTF_FORMAT:
            return "BTF"
        if "plan" in attributes:
            return "capture"
    elif (path / "reflectance").is_dir():
        return "BTF"
    elif any((path / name).is_dir() for name in ("frames", "index", "progress")):
        return "capture"
    fail(
        f"{path} is not a spectwin store (no capture plan, no BTF format attribute): expected a "
        "capture store (spectwin capture) or a BTF store (spectwin process)"
    )


def _source_provenance(source: str | None) -> dict[str, Any]:
    """Seed and program of the capture a BTF was processed from (when it can be read)."""
    from hwbridge.errors import DamagedDataError, InputError
    from hwbridge.schema import RigAttrs
    from hwbridge.store import CaptureStore

    if not source:
        return {"seed": None, "program": None}
    try:
        capture = CaptureStore.open(source)
        seed, rig = capture.metadata.seed, capture.rig_attrs(RigAttrs)
    except (InputError, DamagedDataError):
        return {"seed": None, "program": "(source capture unreadable)"}
    return {"seed": seed, "program": rig.program}


@store_app.command("check")
def check(
    store: Annotated[
        Path, typer.Argument(help="A capture store (.capture.zarr) or a BTF store (.btf.zarr).")
    ],
    as_json: JsonFlag = False,
) -> None:
    """Check a store: its settings and array shapes are those it was created with, every
    frame or pair flagged done has its chunks, each passes its checksum and is the chunk
    written in its place of this store, the complete flag agrees with the progress flags.
    Exit 0: healthy (complete or resumable); exit 1: damaged, with the first damaged frame or
    pair named.

    Example: spectwin store check out/run.capture.zarr
    """
    from hwbridge.store import CaptureStore
    from recon.btf.store import BTFStore

    kind = _kind(store)
    if kind == "capture":
        report = CaptureStore.open(store).check()
    else:
        report = BTFStore.open(store).check()
        report.provenance |= _source_provenance(report.provenance.get("source_capture"))
    if as_json:
        print_summary(report.as_dict(), "", as_json=True)
    else:
        print_summary(report.summary(), f"store check: {kind} store")
    damage = report.damage()
    if damage:
        run_failed(f"{store} is damaged: {damage}")


def require_sound_capture(capture: Any, path: Path) -> None:
    """Refuse a damaged (exit 1) or incomplete (exit 2) capture store, naming the first bad
    frame; reads every frame's bytes once (checksums, no decompression), before processing."""
    report = capture.check()
    damage = report.damage()
    if damage:
        remedy = (
            f"spectwin capture resume {path} takes its damaged frames again"
            if report.provenance.get("backend") == "sim"
            else "restore it from a copy or capture again"
        )
        run_failed(f"{path}: damaged capture store: {damage}; {remedy}")
    if report.pending:
        fail(
            f"{path}: the capture is incomplete ({len(report.pending)} of {report.total} steps "
            f"pending, first step {report.pending[0]}); finish it with spectwin capture resume "
            f"{path}"
        )


def require_sound_btf(
    path: Path, action: str, *, allow_unregistered: bool = False, compressed: bool = False
) -> None:
    """Refuse a damaged (exit 1) or incomplete (exit 2) BTF store before ``action``.

    Parameters
    ----------
    path
        The BTF store.
    action
        What the command does with it (``"compress"``), for the message.
    allow_unregistered
        Accept pairs left pending because processing found no registration marks (listed in
        ``unregistered_pairs``: evaluate and validate leave them out).
    compressed
        The command reads the compressed form (``pca/``), whose damage then counts too.
    """
    from recon.btf.store import BTFStore

    report = BTFStore.open(path).check()
    relevant = [problem for problem in report.problems if problem.units or compressed]
    damage = dataclasses.replace(report, problems=relevant).damage()
    if damage:
        remedy = (
            "compress again"
            if not any(problem.units for problem in relevant) and relevant
            else "process the capture again with --resume"
        )
        run_failed(f"{path}: damaged BTF store: {damage}; {remedy}")
    pending = report.pending
    if allow_unregistered:
        unregistered = set(BTFStore.open(path).metadata.unregistered_pairs or ())
        pending = [pair for pair in pending if pair not in unregistered]
    if pending:
        fail(
            f"{path}: cannot {action} an incomplete BTF store ({len(pending)} of "
            f"{report.total} pairs pending, first {pending[:5]}); finish it with spectwin "
            "process --resume"
        )


def register(app: typer.Typer) -> None:
    """Add the ``store`` command group to ``app``."""
    app.add_typer(store_app, name="store")
