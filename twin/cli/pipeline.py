"""``spectwin`` commands of the pipeline after a capture: calibrate, process, compress,
evaluate, validate, for every kind of rig (:mod:`twin.kinds.registry`: what a command does with
a store is found by the rig the store records).

A full twin run at reduced sampling (thesis 3.3 and 4.1)::

    spectwin capture gonio-calibration out/cal.capture.zarr
    spectwin calibrate out/cal.capture.zarr --out out/cal.json
    spectwin capture gonio-run out/run.capture.zarr --calibration out/cal.json
    spectwin process out/run.capture.zarr --calibration out/cal.json --out out/cc.btf.zarr
    spectwin compress out/cc.btf.zarr --layout joint
    spectwin evaluate out/cc.btf.zarr --figure out/cc_vs_truth.png
    spectwin validate out/cc.btf.zarr --out out/validation

The dome's::

    spectwin capture dome-calibration out/cal.capture.zarr --leds 24 --rgb-cameras 3
    spectwin calibrate out/cal.capture.zarr --out out/dome_cal.npz
    spectwin capture dome-run out/lego.capture.zarr --material lego --stage-positions 2 \\
        --leds 24 --rgb-cameras 3
    spectwin process out/lego.capture.zarr --calibration out/dome_cal.npz --out out/lego.btf.zarr
    spectwin evaluate out/lego.btf.zarr --figure out/lego_vs_truth.png
"""

from __future__ import annotations

import shlex
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from twin.cli.choices import EncodingOption
from twin.cli.errors import (
    INTERRUPTED,
    fail,
    require_output_file,
    require_output_folder,
    run_failed,
)
from twin.cli.given import given, option_name
from twin.cli.output import JsonFlag, SchedulerOption, WorkersOption, console, print_summary
from twin.cli.points import parse_circle, parse_corners
from twin.cli.store import require_sound_btf, require_sound_capture

__all__ = ["register"]


class Layout(StrEnum):
    per_band = "per_band"
    joint = "joint"


def _refuse_unused(ctx: typer.Context, names: tuple[str, ...], used: frozenset[str], what: str):
    """Refuse an option of ``names`` given on the command line that ``used`` does not hold."""
    for name in names:
        if name not in used and given(ctx, name):
            fail(f"{option_name(ctx, name)} is not used by {what}; leave it out")


def _show(outcome, as_json: bool) -> None:
    """Print a rig hook's outcome; a failure exits 1 after the summary."""
    summary = outcome.as_json if as_json and outcome.as_json is not None else outcome.summary
    print_summary(summary, outcome.title, as_json)


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
    the RGB cameras' response curves, the white standard under every LED, the LED spectrum from
    the spectrometer's readings of the white standard and every RGB camera's spectral response
    from its photograph of the colour chart (chapter 9), with a figure of both.

    Example: spectwin calibrate out/cal.capture.zarr --out out/cal.json
    """
    from hwbridge.store import CaptureStore
    from twin.kinds.registry import capture_rig_kind

    capture = CaptureStore.open(store)
    kind = capture_rig_kind(capture)
    _refuse_unused(ctx, ("white_fill",), kind.calibrate_options, f"a {kind.name} calibration")
    out = kind.calibration_file if out is None else out
    if kind.calibration_suffix is not None and out.suffix != kind.calibration_suffix:
        fail(
            f"--out {out}: a {kind.name} calibration is a {kind.calibration_suffix} file; "
            f"expected a name ending in {kind.calibration_suffix}"
        )
    require_output_file(out)
    require_sound_capture(capture, store)
    options = {"white_fill": white_fill}
    _show(kind.calibrate(capture, out, options, not as_json), as_json)


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
            "inside every chart field). Default: 128 (gonio), the capture's texels (dome); "
            "with --resume, the store's (another is refused).",
        ),
    ] = None,
    manual_corners: Annotated[
        Path | None, typer.Option(help="Manual corner file for frames detection misses.")
    ] = None,
    resume: Annotated[
        bool,
        typer.Option(
            "--resume",
            help="Continue an interrupted process, from the capture store, calibration and "
            "texels it began with.",
        ),
    ] = False,
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    p_dyn: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            max=1.0,
            help="dome: Eq. 10.2's exponent of the joint solve (default 0: on the twin's dome "
            "stores the thesis's 0.5-0.6 did worse for three materials of four, 1 % better for "
            "the fourth).",
        ),
    ] = None,
    band_registration: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            max=10.0,
            help="dome: how far (texels) the spectral camera's bands may lie from the RGB "
            "camera's view of the same surface; texels where that would change a band much "
            "(edges, dark lines beside bright ones) weigh less in the joint solve (default "
            "0.25; 0: every texel alike, as the thesis).",
        ),
    ] = None,
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
    from recon.registration.border import read_manual_corners
    from twin.kinds.registry import capture_rig_kind

    # Everything that can be checked is, before the first frame is read: the options, the
    # calibration, the output, the store's integrity and progress, its kind and bands.
    require_output_folder(out)
    if out.resolve() == store.resolve():
        fail(f"--out {out} is the capture store itself; choose another --out")
    require_no_writer(out)
    if not resume:
        require_new_store(out)
    capture = CaptureStore.open(store)
    kind = capture_rig_kind(capture)
    _refuse_unused(
        ctx,
        ("workers", "scheduler", "p_dyn", "band_registration"),
        kind.process_options,
        f"a {kind.name} run",
    )
    options = {
        "texels": texels,
        "manual_corners": read_manual_corners(manual_corners) if manual_corners else None,
        "resume": resume,
        "workers": workers,
        "scheduler": scheduler,
        "p_dyn": p_dyn,
        "band_registration": band_registration,
    }
    require_sound_capture(capture, store)
    try:
        outcome = kind.process(capture, calibration, out, options, not as_json)
    except KeyboardInterrupt:
        again = ["spectwin", "process", str(store), "--calibration", str(calibration)]
        again += ["--out", str(out)] + ([] if texels is None else ["--texels", str(texels)])
        typer.echo(f"interrupted; continue with: {shlex.join([*again, '--resume'])}", err=True)
        raise typer.Exit(INTERRUPTED) from None
    _show(outcome, as_json)
    if outcome.failure is not None:
        run_failed(f"{outcome.failure}, and run again with --manual-corners FILE --resume")


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
    from twin.kinds.registry import btf_rig_kind

    if figure is not None:
        require_output_file(figure, "--figure")
    require_sound_btf(btf, "evaluate", allow_unregistered=True)
    kind = btf_rig_kind(btf)
    with console.status("rendering the truth and comparing"):
        outcome = kind.evaluate(btf, spp, figure)
    _show(outcome, as_json)


def validate(
    ctx: typer.Context,
    btf: Annotated[Path, typer.Argument(help="A BTF store.")],
    out: Annotated[Path, typer.Option(help="Folder for the figures and metrics.json.")] = Path(
        "validation"
    ),
    photo: Annotated[
        Path | None,
        typer.Option(
            help="Your photograph of the sample: a camera raw file, or a linear TIFF, PNG or "
            "OpenEXR image (without it: the twin's photograph of its material in its room)."
        ),
    ] = None,
    environment: Annotated[
        Path | None,
        typer.Option(
            help="With --photo: the light at the sample, a lat-long OpenEXR map (2:1), spectral "
            "or RGB (upsampled), +z the sample's normal."
        ),
    ] = None,
    mirror_sphere: Annotated[
        Path | None,
        typer.Option(
            help="With --photo, instead of --environment: a photograph of a mirror sphere where "
            "the sample lay, taken by the same camera from the same place."
        ),
    ] = None,
    sphere_circle: Annotated[
        str | None,
        typer.Option(help="With --mirror-sphere: the sphere's 'x,y,radius' in its pixels."),
    ] = None,
    sample_corners: Annotated[
        str | None,
        typer.Option(
            help="With --photo: the sample's corners 'x,y;x,y;x,y;x,y' in the photograph's "
            "pixels, in the order of the BTF's texture: top left, top right, bottom right, "
            "bottom left."
        ),
    ] = None,
    fov_deg: Annotated[
        float | None,
        typer.Option(
            help="With --photo: its horizontal field of view in degrees (default: from the "
            "file's 35 mm equivalent focal length)."
        ),
    ] = None,
    camera: Annotated[
        str,
        typer.Option(
            help="With --photo: the camera's response, a measured camera by name (e.g. 'Nikon "
            "D850'), a CSV wavelength_nm,R,G,B (spectwin camchar writes one), or srgb-linear."
        ),
    ] = "srgb-linear",
    exposure: Annotated[
        float | None,
        typer.Option(
            help="With --photo: the photograph's value of a unit of the map's radiance "
            "(default: fitted over the sample)."
        ),
    ] = None,
    encoding: EncodingOption = None,
    compressed: Annotated[
        bool, typer.Option("--compressed", help="Render the store's PCA form (spectwin compress).")
    ] = False,
    pixels: Annotated[
        int,
        typer.Option(
            min=23,
            max=2048,
            help="Image size of the panels (the twin's: square, at least 23 so that every chart "
            "field keeps an interior pixel; with --photo: its longer side, reduced to it).",
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
            min=4,
            max=2048,
            help="Rows of the environment map captured or unwrapped from a mirror sphere (2x as "
            "many columns).",
        ),
    ] = 64,
    map_spp: Annotated[
        int,
        typer.Option(
            min=4,
            max=65536,
            help="Without --photo: samples per pixel of the twin's mirror-sphere image the map "
            "is captured from (8 x --map-height pixels across).",
        ),
    ] = 64,
    as_json: JsonFlag = False,
) -> None:
    """Render the BTF back (thesis 4.2, Figure 4.6): a photograph of the sample, the BTF
    rendered spectrally and in RGB where it was taken, Delta E94 maps and a metrics JSON. With
    --photo, your photograph, the light where you took it and the sample's corners in it;
    without, the twin's photograph of its material in its room (written as photograph.exr and
    environment.exr, with the corners, for --photo), and for a chart the 45/0
    spectrophotometer comparison.

    Example: spectwin validate s.btf.zarr --photo IMG.tif --environment room.exr
    --sample-corners '810,420;1630,440;1650,1210;790,1190' --fov-deg 40
    """
    require_output_folder(out)
    require_sound_btf(btf, "validate", allow_unregistered=True, compressed=compressed)
    photo_only = [
        option_name(ctx, name)
        for name in (
            "environment",
            "mirror_sphere",
            "sphere_circle",
            "sample_corners",
            "fov_deg",
            "camera",
            "exposure",
            "encoding",
        )
        if given(ctx, name)
    ]
    if photo is None:
        if photo_only:
            fail(f"{', '.join(photo_only)}: only with --photo (your photograph)")
        _validate_twin(btf, out, compressed, pixels, spp, map_height, map_spp, as_json)
        return
    if given(ctx, "map_spp"):
        fail("--map-spp: only without --photo (the twin captures its room's map)")
    if sample_corners is None or (environment is None) == (mirror_sphere is None):
        fail("--photo: expected --sample-corners and one light: --environment or --mirror-sphere")
    if (mirror_sphere is None) != (sphere_circle is None):
        fail("--mirror-sphere, --sphere-circle: expected both (the photograph and its circle)")
    from twin.validate.photo_validation import read_photo_inputs, validate_photo
    from twin.validate.sphere_probe import MirrorSphere

    light: Path | MirrorSphere = (
        MirrorSphere(mirror_sphere, parse_circle(sphere_circle, "--sphere-circle"))
        if mirror_sphere is not None and sphere_circle is not None
        else Path(str(environment))
    )

    with console.status("reading the photograph and the light") as status:
        inputs = read_photo_inputs(
            photo,
            light,
            parse_corners(sample_corners, "--sample-corners"),
            camera=camera,
            fov_deg=fov_deg,
            pixels=pixels,
            encoding=encoding.value if encoding is not None else None,
            map_height=map_height,
        )
        metrics = validate_photo(
            btf,
            inputs,
            out,
            compressed=compressed,
            spp=spp,
            exposure=exposure,
            step=lambda name: status.update(name),
        )
    if as_json:
        print_summary(metrics, "", as_json)
        return
    found = metrics["validation"]
    summary = {
        "out": str(out),
        "measured_as": metrics["measured_as"],
        "exposure": metrics["exposure"],
        "corners_reprojection_px": metrics["corners_reprojection_px"],
        "extrapolated": "; ".join(metrics["extrapolated"]) or "nothing",
        "mean_delta_e94_spectral": found["mean_delta_e94_spectral"],
        "mean_delta_e94_rgb": found["mean_delta_e94_rgb"],
        "median_delta_e94_spectral": found["median_delta_e94_spectral"],
        "median_delta_e94_rgb": found["median_delta_e94_rgb"],
    }
    print_summary(summary, "BTF rendered where the photograph was taken")


def _validate_twin(
    btf: Path,
    out: Path,
    compressed: bool,
    pixels: int,
    spp: int,
    map_height: int,
    map_spp: int,
    as_json: bool,
) -> None:
    """``spectwin validate`` without --photo: the twin's photograph of the store's material."""
    from recon.btf.store import BTFStore
    from twin.kinds.registry import rig_kind
    from twin.validate.render_back import validate_btf

    rig = BTFStore.open(btf).metadata.rig  # None: imported, narrow bands
    with console.status("validating") as status:
        metrics = validate_btf(
            btf,
            out,
            compressed=compressed,
            pixels=pixels,
            spp=spp,
            map_height=map_height,
            map_spp=map_spp,
            passbands=None if rig is None else rig_kind(rig).passbands,
            step=lambda name: status.update(name),
        )
    if as_json:
        print_summary(metrics, "", as_json)
        return
    figure46, replay = metrics["figure46"], metrics["photo_inputs"]
    summary = {
        "out": str(out),
        "form": metrics["form"],
        "measured_as": metrics["measured_as"],
        **{
            key: value
            for key, value in figure46.items()
            if key.startswith(("field_mean", "field_ratio", "mean_delta"))
        },
    }
    if "spectrophotometer_45_0" in metrics:
        forty_five = metrics["spectrophotometer_45_0"]
        summary["45/0_mean_error_matte_fields_pct"] = forty_five["mean_error_matte_fields_pct"]
        summary["45/0_max_error_matte_fields_pct"] = forty_five["max_error_matte_fields_pct"]
    summary["replay with files"] = (
        f"spectwin validate {shlex.quote(str(btf))} --photo {shlex.quote(replay['photo'])} "
        f"--environment {shlex.quote(replay['environment'])} "
        f"--sample-corners '{replay['sample_corners']}' "
        f"--fov-deg {replay['fov_deg']:g} --exposure 1"
    )
    print_summary(summary, "BTF rendered back (Figure 4.6)")


def register(app: typer.Typer) -> None:
    """Add the commands to ``app``."""
    for command in (calibrate, process, compress, evaluate, validate):
        app.command()(command)
