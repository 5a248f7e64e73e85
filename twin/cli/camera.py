"""``spectwin camera``: bench-test a twin camera, compare it with a real EMVA 1288 measurement,
or fit a twin camera to one.

- ``spectwin camera NAME``: the simulated bench test (photon transfer, dark frames, flicker);
- ``spectwin camera NAME --emva``: the camera repeats a real EMVA 1288 measurement; both are
  analysed by the ``emva1288`` package and printed side by side;
- ``spectwin camera fit DESCRIPTOR --out CAMERA.yaml``: a twin camera fitted to a real
  measurement.

``camera`` is a group whose first argument is either a subcommand (``fit``, ``bench``) or a camera
name, which runs ``bench``: so ``spectwin camera coolsnap_k4`` is ``spectwin camera bench
coolsnap_k4``. A camera file named like a subcommand is given by path (``./fit.yaml``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from twin.cli.errors import SpectwinGroup, fail, require_output_file, require_output_folder
from twin.cli.output import JsonFlag, SeedOption, console, print_comparison, print_summary

__all__ = ["register"]

_DEFAULT_COMMAND = "bench"


class CameraGroup(SpectwinGroup):
    """A group whose first argument, when it names no subcommand, is a camera for ``bench``."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            args = [_DEFAULT_COMMAND, *args]
        return super().parse_args(ctx, args)


camera_app = typer.Typer(
    cls=CameraGroup,
    help="Bench-test a twin camera (spectwin camera NAME), compare it with a real EMVA 1288 "
    "measurement (spectwin camera NAME --emva) or fit one to it (spectwin camera fit "
    "DESCRIPTOR --out CAMERA.yaml).",
    no_args_is_help=True,
)

WavelengthOption = Annotated[
    float | None,
    typer.Option(
        min=200.0,
        max=1200.0,
        help="Wavelength of the measurement's light [nm]. fit: 550 by default (the descriptor "
        "does not record it); --emva: the fitted camera's, else 550.",
    ),
]


@camera_app.command(_DEFAULT_COMMAND)
def bench(
    name: Annotated[
        str, typer.Argument(help="Camera file in scenes/cameras (e.g. coolsnap_k4) or a path.")
    ],
    out: Annotated[
        Path,
        typer.Option(help="Folder; results go to OUT/NAME (camera_report.png, summary.json)."),
    ] = Path("out/camera"),
    emva: Annotated[
        bool,
        typer.Option(
            "--emva",
            help="Repeat a real EMVA 1288 measurement with the camera, analyse both with the "
            "emva1288 package and print them side by side (writes the twin's data set, "
            "photon_transfer.png and emva_comparison.json to OUT/NAME).",
        ),
    ] = False,
    descriptor: Annotated[
        Path | None,
        typer.Option(
            help="--emva: the real measurement's descriptor (EMVA1288_Data.txt); default: the "
            "one the camera was fitted to, else the shipped Basler CCD measurement."
        ),
    ] = None,
    wavelength_nm: WavelengthOption = None,
    seed: SeedOption = 0,
    as_json: JsonFlag = False,
) -> None:
    """Bench-test a camera: photon transfer, dark frames, HMI flicker vs exposure time; with
    --emva, against a real EMVA 1288 measurement.

    Example: spectwin camera basler_ccd12 --emva --out out/camera
    """
    from twin.rigs.camera_config import load_camera_config

    if not emva and (descriptor is not None or wavelength_nm is not None):
        fail("--descriptor and --wavelength-nm apply with --emva only")
    config = load_camera_config(name)
    folder = out / Path(name).stem
    require_output_folder(out)
    require_output_folder(folder)
    if emva:
        _emva_comparison(name, folder, descriptor, wavelength_nm, seed, as_json, config.name)
        return
    from twin.studies.camera_bench import run_camera_report

    with console.status(f"simulating {config.name}"):
        summary = run_camera_report(name, folder, seed=seed)
    print_summary(summary, str(summary["camera"]), as_json, skip=("camera", "outputs"))
    if not as_json:
        console.print(f"wrote {folder / 'camera_report.png'}")


def _emva_comparison(
    name: str,
    folder: Path,
    descriptor: Path | None,
    wavelength_nm: float | None,
    seed: int,
    as_json: bool,
    camera: str,
) -> None:
    from twin.output_format import dumps
    from twin.studies.emva_twin import run_emva_comparison

    with console.status(f"{camera}: repeating the EMVA 1288 measurement") as status:
        summary = run_emva_comparison(
            name,
            folder,
            descriptor=descriptor,
            wavelength_nm=wavelength_nm,
            seed=seed,
            step=lambda done, total: status.update(f"{camera}: EMVA 1288 frame {done} of {total}"),
        )
    if as_json:
        typer.echo(dumps(summary))
        return
    shown = {  # differences to a tenth of a percent; the values to four digits
        key: {**row, "difference_percent": round(row["difference_percent"], 1)}
        for key, row in summary["figures"].items()
    }
    print_comparison(
        shown,
        f"EMVA 1288 (emva1288 package): {Path(str(summary['descriptor'])).parent.name} "
        f"against {camera} at {summary['wavelength_nm']:g} nm, seed {seed}",
        ("real", "twin", "difference_percent"),
    )
    limits = summary["dsnu_detection_limit_e"]
    console.print(
        f"DSNU resolved above {limits['real']:.2g} e- (real) and {limits['twin']:.2g} e- (twin)"
    )
    console.print(f"wrote {folder / 'photon_transfer.png'} and the twin's data set in {folder}")


@camera_app.command("fit")
def fit(
    descriptor: Annotated[
        Path, typer.Argument(help="An EMVA 1288 descriptor (EMVA1288_Data.txt) and its images.")
    ],
    out: Annotated[
        Path, typer.Option(help="The camera file to write (YAML, as in scenes/cameras).")
    ],
    name: Annotated[
        str | None, typer.Option(help="The camera's name; default: from the data set's folder.")
    ] = None,
    serial: Annotated[
        str | None,
        typer.Option(help="The serial (it seeds the fixed patterns); default: the folder name."),
    ] = None,
    wavelength_nm: WavelengthOption = None,
    pixel_pitch_um: Annotated[
        float,
        typer.Option(
            min=0.5, max=100.0, help="Pixel pitch [um] (not part of an EMVA 1288 data set)."
        ),
    ] = 7.4,
    source: Annotated[
        str | None,
        typer.Option(help="How the file's header names the measurement; default: its path."),
    ] = None,
    as_json: JsonFlag = False,
) -> None:
    """Fit a twin camera to a real EMVA 1288 measurement (analysed by the emva1288 package):
    gain, quantum efficiency, read noise, offset, dark current, DSNU, PRNU, saturation, OECF.

    Example: spectwin camera fit data/EMVA1288_Data.txt --out my_camera.yaml
    """
    from recon.emva.analysis import analyse_measurement
    from recon.emva.fit import fit_sensor
    from twin.rigs.fitted_camera import write_fitted_camera
    from twin.studies.emva_twin import DEFAULT_WAVELENGTH_NM

    require_output_file(out)
    folder = descriptor.resolve().parent.name
    with console.status(f"analysing {descriptor}"):
        analysis = analyse_measurement(descriptor)
        fitted = fit_sensor(analysis, wavelength_nm=wavelength_nm or DEFAULT_WAVELENGTH_NM)
    config = write_fitted_camera(
        fitted,
        out,
        name=name or f"EMVA 1288 fit of {folder}",
        serial=serial or folder,
        pixel_pitch_um=pixel_pitch_um,
        source=source,
    )
    summary = {"camera": config.name, "file": str(out), **fitted.parameters()}
    print_summary(summary, f"fitted: {config.name}", as_json, skip=("camera",))


def register(app: typer.Typer) -> None:
    """Add the ``camera`` command group to ``app``."""
    app.add_typer(camera_app, name="camera")
