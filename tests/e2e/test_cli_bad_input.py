"""Bad input to every ``spectwin`` command: one line ``error: ...`` on stderr, no traceback, exit
2 for usage errors and 1 for failed runs (damaged data), and nothing rendered or written before
the refusal.

Each probe is ``(arguments, exit code, phrase of the message)``; ``@NAME`` in an argument is a
path of the ``inputs`` fixture (small stores and files made by hand, in about a second).
``python -m tests.e2e.test_cli_bad_input OUT.md`` writes the probes and their messages as a
markdown table.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

from hwbridge.lock import StoreLock
from hwbridge.schema import SCHEMA_VERSION, GonioRigAttrs
from hwbridge.store import CaptureStore, FrameRecord
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app

runner = CliRunner()
SCENES = Path(__file__).resolve().parents[2] / "scenes"
_HELD: list[StoreLock] = []  # the writer locks of the @LOCKED_ stores, held by this process

PROBES: list[tuple[list[str], int, str]] = [
    # info
    (["info", "--bogus"], 2, "No such option: --bogus"),
    (["nosuch"], 2, "No such command 'nosuch'"),
    # smoke
    (["smoke", "--spp", "0"], 2, "'--spp'"),
    (["smoke", "--pixels-per-patch", "2"], 2, "'--pixels-per-patch'"),
    (["smoke", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # camera
    (["camera", "nosuch"], 2, "expected a path or one of ['basler_ccd12', 'coolsnap_k4'"),
    (["camera", "coolsnap_k4", "--seed", "-1"], 2, "'--seed'"),
    (["camera", "@BAD_CAMERA"], 2, "bit_depth"),
    (["camera", "@MALFORMED_YAML"], 2, "malformed YAML"),
    (["camera", "coolsnap_k4", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # estimate
    (["estimate", "nosuch"], 2, "expected a path or one of ['dome', 'gonio']"),
    (["estimate", "@BAD_RIG_CAMERA"], 2, "camera: definition: expected one of"),
    (["estimate", "@BAD_RIG_KIND"], 2, "expected 'gonioreflectometer' or 'dome'"),
    (["estimate", "@MALFORMED_YAML"], 2, "malformed YAML"),
    (["estimate", "@LIST_YAML"], 2, "expected a mapping of settings"),
    # gallery
    (["gallery", "--seed", "-1"], 2, "'--seed'"),
    (["gallery", "--pixels", "8"], 2, "'--pixels'"),
    (["gallery", "--spp", "0"], 2, "'--spp'"),
    (["gallery", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # capture
    (
        ["capture", "@NEW"],
        2,
        "is not a capture program; expected one of demo, gonio-calibration, gonio-run, "
        "dome-calibration, dome-run or resume, then the store",
    ),
    (["capture", "nosuch", "@NEW"], 2, "'nosuch' is not a capture program"),
    (["capture", "demo", "@NEW", "--seed", "-1"], 2, "'--seed'"),
    (["capture", "gonio-run", "@NEW", "--spp", "-3"], 2, "'--spp'"),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@CAL"]
        + ["--window", "64", "--pixels", "32"],
        2,
        "--window 64 is larger than --pixels 32",
    ),
    (["capture", "demo", "@NEW", "--fault-rate", "0.5"], 2, "'--fault-rate'"),
    (["capture", "demo", "@NEW", "--fault-rate", "2"], 2, "'--fault-rate'"),
    (["capture", "demo", "@NEW", "--fault-rate", "nan"], 2, "'--fault-rate'"),
    (["capture", "demo", "@NEW", "--fault-rate", "-0.1"], 2, "'--fault-rate'"),
    (["capture", "demo", "@NEW", "--pixels", "64"], 2, "No such option: --pixels"),
    (["capture", "demo", "@NEW", "--spp", "16"], 2, "No such option: --spp"),
    (["capture", "demo", "@NEW", "--material", "lego"], 2, "No such option: --material"),
    (["capture", "demo", "@NEW", "--window", "32"], 2, "No such option: --window"),
    (["capture", "demo", "@NEW", "--calibration", "@CAL"], 2, "No such option: --calibration"),
    (["capture", "demo", "@NEW", "--program", "demo"], 2, "No such option: --program"),
    (
        ["capture", "gonio-calibration", "@NEW", "--fault-rate", "0.05"],
        2,
        "No such option: --fault-rate",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--dry-run"] + ["--window", "64", "--pixels", "32"],
        2,
        "--window 64 is larger than --pixels 32",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@CAL"]
        + ["--pixels", "4096", "--window", "512"],
        2,
        "pixels: expected 1..2048 pixels across the field of the Photometrics CoolSNAP K4",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@CAL", "--pixels", "4096"],
        2,
        "pixels: expected 1..2048",
    ),
    (["capture", "demo", "@NEW", "--dry-run", "--seed", "3"], 2, "--seed is not used by --dry-run"),
    (["capture", "resume", "@NEW", "--dry-run"], 2, "No such option: --dry-run"),
    (
        ["capture", "resume", "@NEW"],
        2,
        "does not exist: start the capture with spectwin capture PROGRAM",
    ),
    (["capture", "resume", "@INCOMPLETE_CAPTURE", "--seed", "3"], 2, "No such option: --seed"),
    (
        ["capture", "resume", "@INCOMPLETE_CAPTURE", "--program", "gonio-calibration"],
        2,
        "No such option: --program",
    ),
    (["capture", "resume", "@INCOMPLETE_CAPTURE", "--pixels", "64"], 2, "No such option: --pixels"),
    (["capture", "resume", "@LOCKED_CAPTURE"], 1, "is being written by PID"),
    (["capture", "demo", "@LOCKED_CAPTURE"], 1, "is being written by PID"),
    (["capture", "demo", "@LOCKED_NEW"], 1, "is being created by PID"),
    (["capture", "resume", "@LOCKED_NEW"], 1, "is being created by PID"),
    (
        ["capture", "gonio-run", "@NEW"],
        2,
        "gonio-run needs --calibration (the JSON of spectwin calibrate)",
    ),
    (
        ["capture", "demo", "@CAPTURE"],
        2,
        "overwritten); continue it with spectwin capture resume",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@CAL", "--material", "nosuch"],
        2,
        "material: no file",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@CAL_MISSING_KEY"],
        2,
        "calibration lacks ['base_s']",
    ),
    (
        ["capture", "gonio-run", "@NEW", "--calibration", "@NOSUCH"],
        2,
        "not a readable calibration file",
    ),
    # calibrate
    (["calibrate", "nosuch.zarr"], 2, "nosuch.zarr does not exist: expected a capture store"),
    (["calibrate", "@PLAIN"], 2, "is a file: expected a capture store"),
    (["calibrate", "@EMPTY"], 2, "is not a capture store"),
    (["calibrate", "@INCOMPLETE_CAPTURE"], 2, "the capture is incomplete"),
    (["calibrate", "@CAPTURE"], 2, "no oecf, white frames; expected a calibration capture"),
    (["calibrate", "@CAPTURE", "--white-fill", "1.5"], 2, "'--white-fill'"),
    (["calibrate", "@CAPTURE", "--out", "@EMPTY"], 2, "is a folder; expected a file name"),
    # process
    (
        ["process", "@OLD_CAPTURE", "--calibration", "@CAL", "--out", "@NEW_BTF"],
        2,
        f"old.capture.zarr: a capture store of schema version 0, expected {SCHEMA_VERSION} "
        "(written by another version of the software)",
    ),
    (
        ["process", "@UNVERSIONED_CAPTURE", "--calibration", "@CAL", "--out", "@NEW_BTF"],
        2,
        f"a capture store of schema version none recorded, expected {SCHEMA_VERSION}",
    ),
    (
        ["process", "@EMPTY", "--calibration", "@CAL", "--out", "@NEW_BTF"],
        2,
        "is not a capture store",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL_MISSING_KEY", "--out", "@NEW_BTF"],
        2,
        "calibration lacks ['base_s']",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL_NOT_JSON", "--out", "@NEW_BTF"],
        2,
        "not a readable calibration file",
    ),
    *(
        (
            ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@NEW_BTF"]
            + ["--texels", texels],
            2,
            "'--texels'",
        )
        for texels in ("0", "8", "100000000")
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@NEW_BTF"],
        2,
        "expected a measurement run of the gonioreflectometer",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@BTF"],
        2,
        "(nothing was overwritten); continue it with --resume or choose another name",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@NEW_BTF"]
        + ["--manual-corners", "@NOSUCH"],
        2,
        "cannot read manual corner file",
    ),
    (["process", "@CAPTURE", "--out", "@NEW_BTF"], 2, "Missing option '--calibration'"),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@LOCKED_BTF", "--resume"],
        1,
        "is being written by PID",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@LOCKED_BTF"],
        1,
        "is being written by PID",
    ),
    (["compress", "@LOCKED_BTF"], 1, "is being written by PID"),
    # compress
    (["compress", "@PLAIN"], 2, "is a file: expected a BTF store"),
    (["compress", "@CAPTURE"], 2, "not a BTF store"),
    (["compress", "@INCOMPLETE_BTF"], 2, "finish it with spectwin process --resume"),
    (
        ["compress", "@OLD_BTF"],
        2,
        "a BTF store of format version 1, expected 3 (written by another version of the "
        "software); spectwin process makes one",
    ),
    (["compress", "@DAMAGED_CHUNK_BTF"], 1, "pair 1: reflectance/c/1/0/0/0 is corrupt"),
    (["compress", "@DAMAGED_METADATA_BTF"], 1, "reflectance/zarr.json is unreadable"),
    (["compress", "@BTF", "--brightness", "0"], 2, "'--brightness'"),
    (["compress", "@BTF", "--layout", "nosuch"], 2, "'--layout'"),
    # evaluate
    (["evaluate", "nosuch.btf.zarr"], 2, "does not exist: expected a BTF store"),
    (["evaluate", "@EMPTY_BTF"], 2, "cannot evaluate an incomplete BTF store (2 of 2 pairs"),
    (["evaluate", "@BTF", "--spp", "-4"], 2, "'--spp'"),
    (["evaluate", "@BTF", "--spp", "0"], 2, "'--spp'"),
    (["evaluate", "@BTF", "--figure", "@EMPTY"], 2, "is a folder; expected a file name"),
    (["evaluate", "@BTF"], 2, "records no source capture"),
    (["evaluate", "@IMPORTED_BTF"], 2, "a BTF store that no rig of spectwin processed (imported)"),
    (["evaluate", "@DAMAGED_METADATA_BTF"], 1, "damaged store"),
    # validate
    (["validate", "@BTF", "--pixels", "8"], 2, "'--pixels'"),
    (["validate", "@BTF", "--spp", "0"], 2, "'--spp'"),
    (["validate", "@EMPTY_BTF", "--out", "@NEW_FOLDER"], 2, "cannot validate an incomplete BTF"),
    (["validate", "@BTF", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    (["validate", "@SMALL_BTF", "--out", "@NEW_FOLDER"], 2, "without a texel in the 45/0"),
    (["validate", "@BTF", "--compressed", "--out", "@NEW_FOLDER"], 2, "no compressed form"),
    (["validate", "@EMPTY", "--out", "@NEW_FOLDER"], 2, "not a BTF store"),
    # store check
    (["store", "check", "nosuch.zarr"], 2, "does not exist: expected a capture store or a BTF"),
    (["store", "check", "@PLAIN"], 2, "is a file: expected a capture store or a BTF store"),
    (["store", "check", "@EMPTY"], 2, "is not a spectwin store"),
    (["store", "check", "@CAPTURE", "--bogus"], 2, "No such option: --bogus"),
    (
        ["store", "check", "@OLD_CAPTURE"],
        2,
        f"a capture store of schema version 0, expected {SCHEMA_VERSION}",
    ),
    (
        ["store", "check", "@UNVERSIONED_CAPTURE"],
        2,
        f"schema version none recorded, expected {SCHEMA_VERSION}",
    ),
    (["store", "check", "@OLD_BTF"], 2, "old.btf.zarr: a BTF store of format version 1, expected"),
    (["store", "nosuch"], 2, "No such command 'nosuch'"),
    # camchar-study
    (["camchar-study", "--camera", "nosuch"], 2, "'Nikon D70'"),
    (["camchar-study", "--light", "candle"], 2, "'daylight'"),
    (["camchar-study", "--chart", "nosuch"], 2, "'esser'"),
    (["camchar-study", "--bend", "0.5"], 2, "'--bend'"),
    (["camchar-study", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # camchar-cameras
    (["camchar-cameras", "--camera", "Nikon D85"], 2, "closest: Nikon D850"),
    (["camchar-cameras", "--seed", "-1"], 2, "'--seed'"),
    (["camchar-cameras", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # spectralize-study
    (["spectralize-study", "--texels", "16", "--no-sweeps"], 2, "'--texels'"),
    (["spectralize-study", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # dome-study
    (["dome-study", "--seed", "-1"], 2, "'--seed'"),
    (["dome-study", "--texels", "10"], 2, "--texels 10: expected a multiple of 4"),
    (["dome-study", "--texels", "4"], 2, "'--texels'"),
    (["dome-study", "--material", "nosuch"], 2, "'lego'"),
    (
        ["dome-study", "--capture-texels", "32", "--store-texels", "64"],
        2,
        "--store-texels 64: expected at most --capture-texels 32",
    ),
    (
        ["dome-study", "--analytic-only", "--error-budget"],
        2,
        "--analytic-only, --error-budget: the error budget is the dome stores'",
    ),
    (["dome-study", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    # demo
    (["demo", "--out", "@PLAIN"], 2, "is a file; expected a folder"),
    (["demo", "--out", "@FULL_FOLDER"], 2, "is not empty and was not written by spectwin demo"),
    (["demo", "--bogus"], 2, "No such option: --bogus"),
]


def _capture(path: Path, *, complete: bool) -> None:
    """A store of two dark frames (both written when ``complete``)."""
    plan = [{"camera": "k4", "kind": "dark", "exposure_s": 0.1}] * 2
    store = CaptureStore.create(
        path,
        rig=GonioRigAttrs(
            rig="gonioreflectometer",
            program="demo",
            camera="coolsnap_k4",
            camera_id="k4",
            window_px=4,
            lamp="hmi",
        ),
        backend="sim",
        seed=0,
        plan=plan,
        cameras={"k4": (4, 4)},
    )
    for step in range(2 if complete else 1):
        store.write_frame(step, np.full((4, 4), 100, np.uint16), FrameRecord("dark", 0.1, 0.0))
        store.mark_done(step)


def _btf(
    path: Path, *, written: int, texels: int = 16, rig: str | None = "gonioreflectometer"
) -> None:
    """A 2-pair BTF of the colour checker, ``written`` pairs written, recording ``rig`` as
    spectwin process does (``None``: as an imported BTF)."""
    directions = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)]])
    store = BTFStore.create(
        path,
        light_dirs=directions,
        view_dirs=directions[::-1],
        texels=texels,
        grid=DEFAULT_GRID,
        material="colorchecker16",
        rig=rig,
    )
    for pair in range(written):
        store.write_pair(pair, np.full((texels, texels, DEFAULT_GRID.size), 0.2, np.float32))


def _with_version(path: Path, attribute: str, version: int | None) -> None:
    """The store at ``path`` as another version of spectwin wrote it: its version ``attribute``
    set to ``version`` (``None``: left out, as before stores recorded it)."""
    group = zarr.open_group(str(path), mode="r+")
    if version is None:
        del group.attrs[attribute]
    else:
        group.attrs[attribute] = version


def make_inputs(root: Path) -> dict[str, Path]:
    """The files and stores the probes name."""
    paths = {
        name: root / file
        for name, file in {
            "PLAIN": "plain.txt",
            "EMPTY": "empty",
            "FULL_FOLDER": "full",
            "NEW": "new.capture.zarr",
            "NEW_BTF": "new.btf.zarr",
            "NEW_FOLDER": "new_folder",
            "NOSUCH": "nosuch.json",
            "CAL": "cal.json",
            "CAL_MISSING_KEY": "cal_missing_key.json",
            "CAL_NOT_JSON": "cal_not_json.json",
            "CAPTURE": "done.capture.zarr",
            "INCOMPLETE_CAPTURE": "half.capture.zarr",
            "BTF": "cc.btf.zarr",
            "IMPORTED_BTF": "imported.btf.zarr",
            "EMPTY_BTF": "empty.btf.zarr",
            "INCOMPLETE_BTF": "half.btf.zarr",
            "SMALL_BTF": "small.btf.zarr",
            "DAMAGED_CHUNK_BTF": "damaged_chunk.btf.zarr",
            "DAMAGED_METADATA_BTF": "damaged_metadata.btf.zarr",
            "BAD_CAMERA": "bad_camera.yaml",
            "BAD_RIG_CAMERA": "bad_rig_camera.yaml",
            "BAD_RIG_KIND": "bad_rig_kind.yaml",
            "MALFORMED_YAML": "malformed.yaml",
            "LIST_YAML": "list.yaml",
            "LOCKED_CAPTURE": "locked.capture.zarr",
            "LOCKED_NEW": "locked_new.capture.zarr",
            "LOCKED_BTF": "locked.btf.zarr",
            "OLD_CAPTURE": "old.capture.zarr",
            "UNVERSIONED_CAPTURE": "unversioned.capture.zarr",
            "OLD_BTF": "old.btf.zarr",
        }.items()
    }
    paths["PLAIN"].write_text("not a store\n")
    paths["EMPTY"].mkdir()
    paths["FULL_FOLDER"].mkdir()
    (paths["FULL_FOLDER"] / "notes.txt").write_text("mine\n")
    bands = DEFAULT_GRID.wavelengths_nm
    calibration = GonioCalibration.identity(np.full(bands.size, 2 / 15), bands, 1 / 15)
    calibration.save(paths["CAL"])
    document = paths["CAL"].read_text()
    paths["CAL_MISSING_KEY"].write_text(document.replace('"base_s"', '"base"'))
    paths["CAL_NOT_JSON"].write_text(document[:200])
    _capture(paths["CAPTURE"], complete=True)
    _capture(paths["INCOMPLETE_CAPTURE"], complete=False)
    _btf(paths["BTF"], written=2)
    _btf(paths["IMPORTED_BTF"], written=2, rig=None)
    _btf(paths["EMPTY_BTF"], written=0)
    _btf(paths["INCOMPLETE_BTF"], written=1)
    _btf(paths["SMALL_BTF"], written=2, texels=8)
    for name in ("DAMAGED_CHUNK_BTF", "DAMAGED_METADATA_BTF"):
        _btf(paths[name], written=2)
    _capture(paths["LOCKED_CAPTURE"], complete=False)
    for name, version in (("OLD_CAPTURE", 0), ("UNVERSIONED_CAPTURE", None)):
        _capture(paths[name], complete=True)
        _with_version(paths[name], "schema_version", version)
    _btf(paths["OLD_BTF"], written=2)
    _with_version(paths["OLD_BTF"], "format_version", 1)
    _btf(paths["LOCKED_BTF"], written=1)
    _HELD.append(StoreLock.acquire(paths["LOCKED_CAPTURE"]))
    _HELD.append(StoreLock.acquire(paths["LOCKED_BTF"]))
    _HELD.append(StoreLock.reserve(paths["LOCKED_NEW"]))  # a store being created
    (paths["DAMAGED_CHUNK_BTF"] / "reflectance" / "c" / "1" / "0" / "0" / "0").write_bytes(
        b"\x28\xb5\x2f\xfd not zstd"
    )
    (paths["DAMAGED_METADATA_BTF"] / "reflectance" / "zarr.json").write_text('{"shape": [2,')
    camera = (SCENES / "cameras" / "coolsnap_k4.yaml").read_text()
    paths["BAD_CAMERA"].write_text(camera.replace("bit_depth: 12", "bit_depth: twelve"))
    rig = (SCENES / "rigs" / "gonio.yaml").read_text()
    paths["BAD_RIG_CAMERA"].write_text(rig.replace("definition: coolsnap_k4", "definition: k9"))
    paths["BAD_RIG_KIND"].write_text(rig.replace("rig: gonioreflectometer", "rig: tripod"))
    paths["MALFORMED_YAML"].write_text("name: [unclosed\nrig: dome\n")
    paths["LIST_YAML"].write_text("- gonio\n- dome\n")
    return paths


def _arguments(arguments: list[str], paths: dict[str, Path]) -> list[str]:
    return [str(paths[a[1:]]) if a.startswith("@") else a for a in arguments]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> dict[str, Path]:
    return make_inputs(tmp_path_factory.mktemp("bad_input"))


@pytest.mark.parametrize(
    ("arguments", "code", "phrase"),
    PROBES,
    ids=[" ".join(arguments) for arguments, _, _ in PROBES],
)
def test_bad_input_is_one_line_without_traceback(inputs, arguments, code, phrase):
    result = runner.invoke(app, _arguments(arguments, inputs), prog_name="spectwin")
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert phrase in lines[0]


def test_probes_write_nothing(inputs):
    """No refused command created the stores or folders it was given, or left a lock file."""
    for name in ("NEW", "NEW_BTF", "NEW_FOLDER", "LOCKED_NEW"):
        assert not inputs[name].exists()
    root = inputs["NEW"].parent
    hidden = sorted(path.name for path in root.iterdir() if path.name.startswith("."))
    assert hidden == [".locked_new.capture.zarr.writer.lock"]  # the fixture's reservation
    for name in ("CAPTURE", "INCOMPLETE_CAPTURE", "BTF", "INCOMPLETE_BTF"):
        assert not (inputs[name] / ".writer.lock").exists()
    assert sorted(path.name for path in inputs["EMPTY"].iterdir()) == []
    assert sorted(path.name for path in inputs["FULL_FOLDER"].iterdir()) == ["notes.txt"]


def test_a_device_that_keeps_failing_stops_the_capture_with_exit_1(inputs, monkeypatch):
    from hwbridge.errors import DeviceTimeout

    def failing_session(*args, **kwargs):
        raise DeviceTimeout("simulated timeout of k4.snap")

    monkeypatch.setattr("twin.gonio.capture.CaptureProgram.run", failing_session)
    result = runner.invoke(app, ["capture", "demo", str(inputs["NEW"]), "--workers", "0"])
    assert result.exit_code == 1, result.output
    assert result.stderr.count("\n") == 1 and "spectwin capture resume" in result.stderr
    assert "Traceback" not in result.output


def test_the_option_choices_are_those_of_the_modules():
    from twin.cli.choices import Chart, DomeMaterial, Light, RGBCamera
    from twin.components.detectors import RGB_CAMERA_RESPONSES
    from twin.studies.camchar_scenes import CHARTS, LIGHTS
    from twin.studies.dome import DOME_MATERIALS

    assert sorted(RGBCamera) == sorted(RGB_CAMERA_RESPONSES)
    assert sorted(Chart) == sorted(CHARTS) and sorted(Light) == sorted(LIGHTS)
    assert sorted(DomeMaterial) == sorted(DOME_MATERIALS)


def write_probe_table(out: Path) -> None:
    """Run every probe and write a markdown table of command, exit code and message."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        paths = make_inputs(Path(folder))
        rows = [
            "`@NAME`: a file or store made by `make_inputs` (e.g. `@PLAIN` a plain text file, "
            "`@EMPTY` an empty folder, `@CAPTURE` a complete capture store of two dark frames, "
            "`@BTF` a complete 2-pair BTF store); `…`: its temporary folder.",
            "",
            "| command | exit code | message |",
            "|---|---|---|",
        ]
        for arguments, _, _ in PROBES:
            result = runner.invoke(app, _arguments(arguments, paths), prog_name="spectwin")
            message = result.stderr.strip().replace(folder, "…").replace("|", "\\|")
            shown = " ".join(arguments).replace("|", "\\|")
            rows.append(f"| `spectwin {shown}` | {result.exit_code} | {message} |")
    out.write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    write_probe_table(Path(sys.argv[1] if len(sys.argv) > 1 else "cli_probes.md"))
