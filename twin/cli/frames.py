"""``spectwin export-frames`` and ``spectwin ingest``: a capture store written out as the TIFF
files a rig's own software writes (:mod:`hwbridge.export_frames`), and a folder of frame files,
a real rig's or an export's, read into a capture store through a mapping (:mod:`hwbridge.replay`).

An exported capture comes back through the shipped mapping ``spectwin`` as a store that
calibrates and processes as the original does::

    spectwin export-frames out/run.capture.zarr --out out/run_frames
    spectwin ingest out/run_frames --mapping spectwin --out out/run_again.capture.zarr

Both check everything they can before they write (the store complete, the folder new or empty;
the mapping, every frame readable and alike per camera, every step's frame, the store new): bad
input is one line ``error: ...`` and nothing written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from twin.cli.output import JsonFlag, print_summary

__all__ = ["register"]


def export_frames(
    store: Annotated[Path, typer.Argument(help="A complete capture store (.capture.zarr).")],
    out: Annotated[Path, typer.Option(help="New or empty folder for the frames.")],
    as_json: JsonFlag = False,
) -> None:
    """Write a capture store as a rig's software would: one TIFF per raw frame (kind, exposure,
    band, view and light in its name), a JSON sidecar per frame with its whole record, and
    session.json (rig, seed, backend, plan), written last.

    Example: spectwin export-frames out/run.capture.zarr --out out/run_frames
    """
    from hwbridge.export_frames import prepare_export
    from hwbridge.store import CaptureStore
    from recon.progress import progress_steps

    export = prepare_export(CaptureStore.open(store), out)
    total = sum(export.frames.values())
    with progress_steps("exporting frames", total, enabled=not as_json) as advance:
        written = export.write(advance)
    summary = {
        "store": str(store),
        "out": str(written.folder),
        "rig": written.rig,
        "program": written.program,
        "frames": total,
        "cameras": written.frames,
    }
    print_summary(summary, "frames exported", as_json)


def ingest(
    folder: Annotated[Path, typer.Argument(help="Folder of frame files (TIFF).")],
    mapping: Annotated[
        str,
        typer.Option(
            help="Mapping file, or a shipped mapping's name: spectwin (folders of "
            "export-frames, any rig), llanos2019."
        ),
    ],
    out: Annotated[Path, typer.Option(help="Capture store to write (<name>.capture.zarr).")],
    as_json: JsonFlag = False,
) -> None:
    """Read a folder of frames into a capture store through a mapping: regular expressions
    over the files' paths whose named groups give each frame's camera, kind, step, exposure,
    band, view and light; optionally a JSON sidecar per frame and a session file whose rig,
    seed and plan the store takes. Everything is checked before anything is written.

    Example: spectwin ingest out/run_frames --mapping spectwin --out out/run.capture.zarr
    """
    from hwbridge.replay import prepare_ingest
    from recon.progress import progress_steps

    prepared = prepare_ingest(folder, mapping, out)
    total = len(prepared.plan)
    with progress_steps("ingesting frames", total, enabled=not as_json) as advance:
        store = prepared.write(advance)
    summary = {
        "out": str(store.path),
        "source": str(folder),
        "mapping": prepared.mapping,
        "rig": prepared.rig.get("rig"),
        "program": prepared.rig.get("program"),
        "frames": total,
        "cameras": prepared.frames,
        "complete": store.complete,
    }
    print_summary(summary, "frames ingested", as_json)


def register(app: typer.Typer) -> None:
    """Add ``export-frames`` and ``ingest`` to ``app``."""
    app.command("export-frames")(export_frames)
    app.command("ingest")(ingest)
