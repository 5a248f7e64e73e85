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
"""

from __future__ import annotations

from collections import Counter
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from twin.json_output import dumps

__all__ = ["register"]

console = Console()
JsonFlag = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]
WorkersOption = Annotated[
    int,
    typer.Option(
        min=0,
        help="Worker processes of a local Dask cluster (one thread each); 0 or 1: run in this "
        "process. Same results either way.",
    ),
]
SchedulerOption = Annotated[
    str | None,
    typer.Option(
        envvar="DASK_SCHEDULER_ADDRESS",
        help="Run on the Dask cluster of this scheduler (tcp://host:8786); its workers must "
        "see the stores under the same paths.",
    ),
]


class Program(StrEnum):
    demo = "demo"
    gonio_calibration = "gonio-calibration"
    gonio_run = "gonio-run"


class Layout(StrEnum):
    per_band = "per_band"
    joint = "joint"


def _print(summary: dict[str, object], title: str, as_json: bool) -> None:
    if as_json:
        typer.echo(dumps(summary))
        return
    table = Table("quantity", "value", title=title)
    for key, value in summary.items():
        table.add_row(key, str(value))
    console.print(table)


def _fail(message: str) -> None:
    console.print(f"[red]error:[/red] {message}")
    raise typer.Exit(code=2)


def capture(
    store: Annotated[
        Path, typer.Argument(help="Capture store to write, e.g. out/run.capture.zarr.")
    ],
    program: Annotated[
        Program,
        typer.Option(
            help="demo: darks + 2 pairs x 33 bands of the white standard; gonio-calibration: "
            "darks, response series, white standard; gonio-run: a measurement run "
            "(needs --calibration)."
        ),
    ] = Program.demo,
    calibration: Annotated[
        Path | None, typer.Option(help="spectwin calibrate's JSON: the band exposure plan.")
    ] = None,
    material: Annotated[str, typer.Option(help="Material on the holder.")] = "colorchecker16",
    pixels: Annotated[
        int, typer.Option(help="Pixels across the camera's 20 cm field (rendered sensor).")
    ] = 256,
    window: Annotated[
        int | None,
        typer.Option(help="Read out only the centred window of this many pixels (ROI)."),
    ] = None,
    spp: Annotated[int, typer.Option(help="Samples per pixel of the renders.")] = 64,
    seed: Annotated[int, typer.Option(help="Session seed (noise of every frame).")] = 0,
    resume: Annotated[
        bool, typer.Option("--resume", help="Continue an interrupted session.")
    ] = False,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Demo program: print the plan and its duration.")
    ] = False,
    fault_rate: Annotated[
        float, typer.Option(help="Demo program: injected device faults per call (0-1).")
    ] = 0.0,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    as_json: JsonFlag = False,
) -> None:
    """Capture a simulated gonioreflectometer session into a capture store (resumable).

    With --workers N (a local cluster) or --scheduler ADDRESS the steps run as Dask tasks, view
    by view; the frames are bit-identical to a capture in one process.

    Example: spectwin capture out/run.capture.zarr --program gonio-run --calibration cal.json
    """
    from hwbridge.errors import BridgeInputError
    from hwbridge.plans import estimate_duration_s
    from recon.errors import SpectwinInputError
    from twin.cluster import cluster_description, dask_client

    summary: dict[str, object] = {"store": str(store), "program": program.value}
    if program is Program.demo:
        from twin.sim_session import demo_plan

        plan = demo_plan()
        summary["estimated_duration_s"] = round(estimate_duration_s(plan), 1)
        if dry_run:
            summary |= {"steps": len(plan), "kinds": dict(Counter(s["kind"] for s in plan))}
            _print(summary, "capture (dry run)", as_json)
            return
    if program is Program.gonio_run and calibration is None:
        _fail("--program gonio-run needs --calibration (the JSON of spectwin calibrate)")
    try:
        with dask_client(workers, scheduler) as client:
            summary["cluster"] = cluster_description(client)
            if program is Program.demo:
                from twin.sim_session import run_demo_session

                result = run_demo_session(
                    store,
                    seed,
                    resume=resume,
                    fault_rate=fault_rate,
                    show_progress=not as_json,
                    client=client,
                )
            elif program is Program.gonio_calibration:
                from twin.gonio_capture import run_gonio_calibration

                result = run_gonio_calibration(
                    store, seed=seed, resume=resume, show_progress=not as_json, client=client
                )
            else:
                from recon.gonio_calibration import GonioCalibration
                from twin.gonio_capture import run_gonio_measurement

                result = run_gonio_measurement(
                    store,
                    GonioCalibration.load(calibration).planned_exposure_s,
                    material=material,
                    pixels=pixels,
                    window=window,
                    spp=spp,
                    seed=seed,
                    resume=resume,
                    show_progress=not as_json,
                    client=client,
                )
    except (SpectwinInputError, BridgeInputError) as error:
        _fail(str(error))
    index = result.index(result.attrs["plan"][0]["camera"])
    summary |= {
        "complete": result.complete,
        "frames": dict(Counter(index["kind"].tolist())),
        "frames_with_faults": int(sum(status != "ok" for status in index["status"])),
    }
    _print(summary, "capture (simulated backend)", as_json)


def calibrate(
    store: Annotated[Path, typer.Argument(help="A gonio-calibration capture store.")],
    out: Annotated[Path, typer.Option(help="Calibration JSON to write.")] = Path("cal.json"),
    white_fill: Annotated[
        float, typer.Option(help="Fraction of the range the white standard should reach.")
    ] = 0.7,
    as_json: JsonFlag = False,
) -> None:
    """Response curve (Robertson), white factors F' (Eq. 3.3) and the exposure plan (Eq. 3.4,
    multiples of 1/15 s for the HMI lamp) from a calibration capture.

    Example: spectwin calibrate out/cal.capture.zarr --out out/cal.json
    """
    from recon.errors import SpectwinInputError
    from recon.gonio_calibration import calibrate_gonio

    try:
        with console.status("calibrating"):
            result = calibrate_gonio(store, white_fill=white_fill)
    except SpectwinInputError as error:
        _fail(str(error))
    result.save(out)
    summary = {
        "calibration": str(out),
        "bands": int(result.bands_nm.size),
        "base_s": round(result.base_s, 4),
        "planned_exposure_s": np.round(result.planned_exposure_s, 4).tolist(),
        "exposure_per_pair_s": round(float(result.planned_exposure_s.sum()), 3),
        "all_multiples_of_1_15_s": bool(
            np.allclose(result.planned_exposure_s * 15, np.round(result.planned_exposure_s * 15))
        ),
    }
    _print(summary, "gonio calibration", as_json)


def process(
    store: Annotated[Path, typer.Argument(help="A gonio-run capture store.")],
    calibration: Annotated[Path, typer.Option(help="spectwin calibrate's JSON.")],
    out: Annotated[Path, typer.Option(help="BTF store to write (<name>.btf.zarr).")],
    texels: Annotated[int, typer.Option(help="Texture resolution per side.")] = 128,
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
    """Calibrate and register a measurement run into a spectral BTF store (Eq. 3.6, 4.1.2).

    With --workers N (a local cluster) or --scheduler ADDRESS the direction pairs are Dask
    tasks; the BTF is the same as from one process.

    Example: spectwin process out/run.capture.zarr --calibration out/cal.json --out out/cc.btf.zarr
    """
    from recon.errors import SpectwinInputError
    from recon.gonio_calibration import GonioCalibration
    from recon.registration import read_manual_corners
    from twin.cluster import cluster_description, dask_client, run_process

    try:
        corners = read_manual_corners(manual_corners) if manual_corners else None
        with dask_client(workers, scheduler) as client:
            cluster = cluster_description(client)
            btf = run_process(
                store,
                GonioCalibration.load(calibration),
                out,
                texels=texels,
                manual_corners=corners,
                resume=resume,
                show_progress=not as_json,
                client=client,
            )
    except SpectwinInputError as error:
        _fail(str(error))
    summary = {
        "btf": str(out),
        "shape": list(btf.shape),
        "complete": btf.complete,
        "coarse_corner_pairs": btf.attrs["coarse_corner_pairs"],
        "unregistered_pairs": btf.attrs["unregistered_pairs"],
        "cluster": cluster,
    }
    _print(summary, "gonio processing", as_json)
    if summary["unregistered_pairs"]:
        Console(stderr=True).print(
            "[yellow]some pairs were not registered:[/yellow] give their corners in a manual "
            'corner file (keys "pair<i>") and run again with --manual-corners FILE --resume'
        )
        raise typer.Exit(code=1)


def compress(
    btf: Annotated[Path, typer.Argument(help="A complete BTF store (spectwin process).")],
    brightness: Annotated[int, typer.Option(help="PCA components of the brightness.")] = 250,
    spectral: Annotated[
        int, typer.Option(help="PCA components of the normalized spectra (per band or joint).")
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
    from recon.btf_compression import compress_btf, compression_report, save_compressed
    from recon.btf_store import BTFStore
    from recon.errors import SpectwinInputError

    try:
        store = BTFStore.open(btf, writable=True)
        with console.status("compressing"):
            reflectance = np.asarray(store.reflectance())
            compressed = compress_btf(
                reflectance,
                store.grid,
                n_brightness=brightness,
                n_spectral=spectral,
                layout=layout.value,
            )
            save_compressed(store, compressed)
            report = compression_report(compressed, reflectance)
    except SpectwinInputError as error:
        _fail(str(error))
    _print({"btf": str(btf), **report.as_dict()}, "BTF compression", as_json)


def evaluate(
    btf: Annotated[Path, typer.Argument(help="A BTF store made by spectwin process.")],
    figure: Annotated[Path | None, typer.Option(help="PNG of errors and spectra.")] = None,
    spp: Annotated[int, typer.Option(help="Samples per pixel of the truth renders.")] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Compare a processed BTF with the twin's true BTF: per-field Eq. 6.8, corner errors.

    Example: spectwin evaluate out/cc.btf.zarr --figure out/cc_vs_truth.png --json
    """
    from recon.btf_store import BTFStore
    from recon.errors import SpectwinInputError
    from twin.gonio_evaluation import evaluate_gonio
    from twin.gonio_report import write_gonio_figure

    try:
        with console.status("rendering the truth and comparing"):
            result = evaluate_gonio(btf, spp=spp)
    except SpectwinInputError as error:
        _fail(str(error))
    summary = result.summary()
    if figure is not None:
        summary["figure"] = str(write_gonio_figure(result, BTFStore.open(btf), figure))
    _print(summary, "BTF vs the twin's truth", as_json)


def validate(
    btf: Annotated[Path, typer.Argument(help="A BTF store of the twin's colour checker.")],
    out: Annotated[Path, typer.Option(help="Folder for the PNGs and metrics.json.")] = Path(
        "validation"
    ),
    compressed: Annotated[
        bool, typer.Option("--compressed", help="Render the store's PCA form (spectwin compress).")
    ] = False,
    pixels: Annotated[int, typer.Option(help="Image size of the three panels.")] = 96,
    spp: Annotated[
        int, typer.Option(help="Samples per pixel (the photograph's noise adds to Delta E).")
    ] = 256,
    map_height: Annotated[
        int, typer.Option(help="Rows of the captured environment map (2x as many columns).")
    ] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Render the BTF back (thesis 4.2): Figure 4.6 (photograph, spectral and RGB renderings,
    Delta E94 maps) and the 45/0 spectrophotometer comparison, with a metrics JSON.

    Example: spectwin validate out/cc.btf.zarr --out out/validation --compressed
    """
    from recon.errors import SpectwinInputError
    from twin.validation import validate_btf

    try:
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
    except SpectwinInputError as error:
        _fail(str(error))
    figure46, forty_five = metrics["figure46"], metrics["spectrophotometer_45_0"]
    summary = {
        "out": str(out),
        "form": metrics["form"],
        "field_mean_delta_e94_spectral": round(figure46["field_mean_delta_e94_spectral"], 3),
        "field_mean_delta_e94_rgb": round(figure46["field_mean_delta_e94_rgb"], 3),
        "field_ratio_rgb_over_spectral": round(figure46["field_ratio_rgb_over_spectral"], 2),
        "mean_delta_e94_spectral": round(figure46["mean_delta_e94_spectral"], 3),
        "mean_delta_e94_rgb": round(figure46["mean_delta_e94_rgb"], 3),
        "45_0_mean_error_matte_fields_pct": round(forty_five["mean_error_matte_fields_pct"], 3),
        "45_0_max_error_matte_fields_pct": round(forty_five["max_error_matte_fields_pct"], 3),
    }
    _print(metrics if as_json else summary, "BTF rendered back (Figure 4.6, 45/0)", as_json)


def register(app: typer.Typer) -> None:
    """Add the commands to ``app``."""
    for command in (capture, calibrate, process, compress, evaluate, validate):
        app.command()(command)
