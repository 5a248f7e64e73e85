"""Errors of the operating system and implausible files met by ``spectwin`` commands: one line
``error: ...`` naming the path, no traceback, exit 2 for an input or output location that cannot
be read or written (or whose name is too long) and nothing written; a second writer kept out of
a store whose lock file was deleted; Ctrl-C saying what is left and how to continue.

Each probe is ``(arguments, exit code, phrase of the message)``; ``@NAME`` in an argument is a
path of the ``inputs`` fixture, ``@NAME/rest`` a path below it. Probes marked unprivileged run
without the right to override file permissions: as root, in one child process whose bounding
set lacks ``CAP_DAC_OVERRIDE`` and ``CAP_DAC_READ_SEARCH`` (root would otherwise read an
unreadable chunk and write into a read-only folder).
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import typer
import typer.main
from typer.testing import CliRunner

from hwbridge.errors import StoreBusy
from hwbridge.lock import LOCK_NAME, StoreLock
from recon.btf.exchange import export_btf
from recon.btf.store import BTFStore
from tests.e2e.test_cli_bad_input import SCENES, make_inputs
from twin.cli.app import app
from twin.cli.errors import INTERRUPTED, SpectwinGroup, require_output_file

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
_HELD: list[StoreLock] = []
LONG_NAME = "n" * 300
LONG_PATH = "/".join(["d" * 200] * 21)  # 4221 bytes

# (arguments, exit code, phrase): every user may run these
PROBES: list[tuple[list[str], int, str]] = [
    # names over 255 bytes, paths over 4096
    (["capture", "demo", f"@ROOT/{LONG_NAME}.capture.zarr"], 2, "expected names of at most 255"),
    (["btf", "export", "@BTF", "--out", f"@ROOT/{LONG_NAME}"], 2, "expected names of at most 255"),
    (
        ["btf", "import", "@SLICES", "--out", f"@ROOT/{LONG_NAME}.btf.zarr"],
        2,
        "expected names of at most 255",
    ),
    (["calibrate", "@CAPTURE", "--out", f"@ROOT/{LONG_NAME}.json"], 2, "expected names of at most"),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", f"@ROOT/{LONG_NAME}.btf.zarr"],
        2,
        "expected names of at most 255",
    ),
    (["capture", "demo", f"@ROOT/{LONG_PATH}/a.capture.zarr"], 2, "expected at most 4095"),
    (["btf", "export", "@BTF", "--out", f"@ROOT/{LONG_PATH}"], 2, "expected at most 4095"),
    (["btf", "import", "@SLICES", "--out", f"@ROOT/{LONG_PATH}/a.btf.zarr"], 2, "at most 4095"),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", f"@ROOT/{LONG_PATH}/a.btf.zarr"],
        2,
        "expected at most 4095",
    ),
    (["smoke", "--out", "@PLAIN/sub"], 2, "plain.txt is a file, not a folder"),
    # calibration files of the other rig, whole or truncated
    (
        ["process", "@CAPTURE", "--calibration", "@DOME_NPZ", "--out", "@RW/a.btf.zarr"],
        2,
        "binary, not JSON text",
    ),
    (
        ["process", "@CAPTURE", "--calibration", "@TRUNCATED_NPZ", "--out", "@RW/a.btf.zarr"],
        2,
        "binary, not JSON text",
    ),
    # implausible cameras
    (["camera", "@HUGE_CAMERA", "--out", "@RW/camera"], 2, "width: Input should be less than"),
    (["camera", "@LARGE_CAMERA", "--out", "@RW/camera"], 2, "expected at most 268435456 pixels"),
    (["camera", "@GAIN_CAMERA", "--out", "@RW/camera"], 2, "system_gain_dn_per_e"),
    # a writer whose lock file was deleted still holds its store
    (["capture", "resume", "@UNLINKED_CAPTURE"], 1, "its lock file .writer.lock was deleted"),
    (
        ["process", "@CAPTURE", "--calibration", "@CAL", "--out", "@UNLINKED_BTF", "--resume"],
        1,
        "its lock file .writer.lock was deleted",
    ),
    (["compress", "@UNLINKED_BTF"], 1, "its lock file .writer.lock was deleted"),
]

# (arguments, exit code, phrase): without the right to override file permissions
UNPRIVILEGED_PROBES: list[tuple[list[str], int, str]] = [
    # an unreadable chunk
    (["store", "check", "@UNREADABLE_CAPTURE"], 2, "frames/k4/c/0/0/0: Permission denied"),
    (["store", "check", "@UNREADABLE_BTF"], 2, "reflectance/c/1/0/0/0: Permission denied"),
    (
        ["calibrate", "@UNREADABLE_CAPTURE", "--out", "@RW/cal.json"],
        2,
        "frames/k4/c/0/0/0: Permission denied",
    ),
    (
        ["process", "@UNREADABLE_CAPTURE", "--calibration", "@CAL", "--out", "@RW/a.btf.zarr"],
        2,
        "frames/k4/c/0/0/0: Permission denied",
    ),
    (
        ["btf", "export", "@UNREADABLE_BTF", "--out", "@RW/slices"],
        2,
        "reflectance/c/1/0/0/0: Permission denied",
    ),
    # a read-only output folder, refused before any work
    (["calibrate", "@CAPTURE", "--out", "@READ_ONLY/cal.json"], 2, "is not writable"),
    (["evaluate", "@BTF", "--figure", "@READ_ONLY/figure.png"], 2, "is not writable"),
    (["btf", "export", "@BTF", "--out", "@READ_ONLY/slices"], 2, "is not writable"),
    (["btf", "import", "@SLICES", "--out", "@READ_ONLY/a.btf.zarr"], 2, "is not writable"),
    (["demo", "--out", "@READ_ONLY/demo"], 2, "is not writable"),
    (["sweep", "gonio_lamp_filter_sampling", "--out", "@READ_ONLY/sweep"], 2, "is not writable"),
    (["material", "check", "lego", "--out", "@READ_ONLY/material"], 2, "is not writable"),
    (["capture", "demo", "@READ_ONLY/a.capture.zarr"], 2, "is not writable"),
]


def _camera(path: Path, old: str, new: str) -> None:
    """The CoolSNAP K4's file with ``old`` replaced by ``new``."""
    path.write_text((SCENES / "cameras" / "coolsnap_k4.yaml").read_text().replace(old, new))


def _held_without_lock_file(store: Path) -> None:
    """``store`` locked by this process, its lock file deleted by hand."""
    _HELD.append(StoreLock.acquire(store))
    (store / LOCK_NAME).unlink()


def _make_inputs(root: Path) -> dict[str, Path]:
    """The files and stores of ``make_inputs`` and those the probes here name."""
    paths = make_inputs(root) | {"ROOT": root}
    for name in ("RW", "READ_ONLY"):
        paths[name] = root / name.lower()
        paths[name].mkdir()
    paths["READ_ONLY"].chmod(0o555)
    paths["SLICES"] = root / "slices"
    export_btf(BTFStore.open(paths["BTF"]), paths["SLICES"])
    for name, source, chunk in (
        ("UNREADABLE_CAPTURE", "CAPTURE", "frames/k4/c/0/0/0"),
        ("UNREADABLE_BTF", "BTF", "reflectance/c/1/0/0/0"),
        ("UNLINKED_CAPTURE", "INCOMPLETE_CAPTURE", None),
        ("UNLINKED_BTF", "INCOMPLETE_BTF", None),
    ):
        paths[name] = root / f"{name.lower()}{paths[source].name[paths[source].name.find('.') :]}"
        shutil.copytree(paths[source], paths[name])
        if chunk is None:
            _held_without_lock_file(paths[name])
        else:
            (paths[name] / chunk).chmod(0)
    paths["DOME_NPZ"], paths["TRUNCATED_NPZ"] = root / "dome_cal.npz", root / "truncated.npz"
    np.savez_compressed(paths["DOME_NPZ"], summary=np.array('{"format": "dome"}'))
    paths["TRUNCATED_NPZ"].write_bytes(paths["DOME_NPZ"].read_bytes()[:100])
    for name, side in (("HUGE_CAMERA", 10**8), ("LARGE_CAMERA", 60000)):
        paths[name] = root / f"{name.lower()}.yaml"
        _camera(paths[name], "width: 2048\nheight: 2048", f"width: {side}\nheight: {side}")
    paths["GAIN_CAMERA"] = root / "gain.yaml"
    _camera(paths["GAIN_CAMERA"], "system_gain_dn_per_e: 0.2", "system_gain_dn_per_e: 1e30")
    return paths


def _arguments(arguments: list[str], paths: dict[str, Path]) -> list[str]:
    """``arguments`` with ``@NAME`` and ``@NAME/rest`` replaced by the fixture's paths."""
    shown = []
    for argument in arguments:
        if argument.startswith("@"):
            name, _, rest = argument[1:].partition("/")
            argument = str(paths[name] / rest) if rest else str(paths[name])
        shown.append(argument)
    return shown


def _files(root: Path) -> set[Path]:
    """Every path below ``root`` (``os.walk`` does not follow links nor fail on long names)."""
    found = set()
    for folder, folders, files in os.walk(root):
        found |= {Path(folder, name) for name in folders + files}
    return found


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("os_errors")
    paths = _make_inputs(root)
    yield paths
    paths["READ_ONLY"].chmod(0o755)  # so that pytest can remove it
    for name in ("UNREADABLE_CAPTURE", "UNREADABLE_BTF"):
        for chunk in _files(paths[name]):
            chunk.chmod(0o755 if chunk.is_dir() else 0o644)


def _without_dac_override() -> None:
    """In the child before it runs Python: drop the capabilities that let root ignore file
    permissions from the bounding set, which the executed program's capabilities derive from."""
    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (1, 2):  # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        if libc.prctl(24, capability, 0, 0, 0) != 0:  # PR_CAPBSET_DROP
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP)")


_RUN_PROBES = """
import json, sys
from typer.testing import CliRunner
from twin.cli.app import app
results = []
for arguments in json.load(open(sys.argv[1])):
    result = CliRunner().invoke(app, arguments, prog_name="spectwin")
    failed = result.exception is not None and not isinstance(result.exception, SystemExit)
    results.append([result.exit_code, result.stdout, result.stderr, failed])
json.dump(results, open(sys.argv[2], "w"))
"""


def _invoke_all(probes: list[list[str]], folder: Path) -> list[tuple[int, str, str, bool]]:
    """Run ``probes`` as a user whom file permissions bind: ``(exit code, stdout, stderr,
    traceback)`` each."""
    if os.geteuid() != 0:
        return [_invoke(arguments) for arguments in probes]
    (folder / "probes.json").write_text(json.dumps(probes))
    subprocess.run(
        [sys.executable, "-c", _RUN_PROBES, folder / "probes.json", folder / "results.json"],
        check=True,
        cwd=ROOT,
        env=os.environ | {"PYTHONPATH": str(ROOT)},
        preexec_fn=_without_dac_override,
    )
    return [tuple(result) for result in json.loads((folder / "results.json").read_text())]


def _invoke(arguments: list[str]) -> tuple[int, str, str, bool]:
    result = runner.invoke(app, arguments, prog_name="spectwin")
    failed = result.exception is not None and not isinstance(result.exception, SystemExit)
    return result.exit_code, result.stdout, result.stderr, failed


@pytest.fixture(scope="module")
def unprivileged(inputs, tmp_path_factory):
    """The unprivileged probes' results and the paths below the fixture's folder before and
    after them, by the probes' ids."""
    before = _files(inputs["ROOT"])
    probes = [_arguments(arguments, inputs) for arguments, _, _ in UNPRIVILEGED_PROBES]
    results = _invoke_all(probes, tmp_path_factory.mktemp("unprivileged"))
    return (
        dict(zip(_ids(UNPRIVILEGED_PROBES), results, strict=True)),
        before,
        _files(inputs["ROOT"]),
    )


def _ids(probes: list[tuple[list[str], int, str]]) -> list[str]:
    return [" ".join(arguments)[:120] for arguments, _, _ in probes]


def _one_line(result: tuple[int, str, str, bool], code: int, phrase: str) -> None:
    """``result`` is one line ``error: ...`` with ``phrase``, exit ``code``, no traceback."""
    exit_code, stdout, stderr, failed = result
    assert not failed and "Traceback" not in stderr, stderr
    assert exit_code == code, stderr
    assert stdout == ""
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr
    assert phrase in lines[0], lines[0]


@pytest.mark.parametrize(("arguments", "code", "phrase"), PROBES, ids=_ids(PROBES))
def test_refused_in_one_line_with_nothing_written(inputs, arguments, code, phrase):
    before = _files(inputs["ROOT"])
    _one_line(_invoke(_arguments(arguments, inputs)), code, phrase)
    assert _files(inputs["ROOT"]) == before


@pytest.mark.parametrize(
    ("arguments", "code", "phrase"), UNPRIVILEGED_PROBES, ids=_ids(UNPRIVILEGED_PROBES)
)
def test_unreadable_inputs_and_read_only_outputs(unprivileged, arguments, code, phrase):
    results, before, after = unprivileged
    _one_line(results[_ids([(arguments, code, phrase)])[0]], code, phrase)
    assert after == before  # no probe wrote anything


def _leaf_commands() -> list[tuple[str, SpectwinGroup, str]]:
    """``(path, group, name)`` of every command of ``spectwin`` that is not a group."""
    found, groups = [], [("spectwin", typer.main.get_command(app))]
    while groups:
        path, group = groups.pop()
        assert isinstance(group, SpectwinGroup)
        for name, command in group.commands.items():
            if isinstance(command, SpectwinGroup):
                groups.append((f"{path} {name}", command))
            else:
                found.append((f"{path} {name}", group, name))
    return found


LEAF_COMMANDS = _leaf_commands()


@pytest.mark.parametrize(
    ("group", "name"),
    [(group, name) for _, group, name in LEAF_COMMANDS],
    ids=[path for path, _, _ in LEAF_COMMANDS],
)
def test_lock_refusals_advise_resume_only_where_the_command_has_it(group, name):
    """A store that another writer holds: ``compress``, ``sweep``, ... advise no ``--resume``."""
    context = group.context_class(group)
    context.invoked_subcommand = name
    advice = group.advice(context, StoreBusy.remedy) or ""
    has_resume = any("--resume" in param.opts for param in group.commands[name].params)
    assert ("--resume" in advice) == has_resume, advice


def test_ctrl_c_in_export_and_import_leaves_nothing(inputs, monkeypatch):
    """Interrupted after the first slice or pair: the partial output is removed, and the line
    says that nothing was written and how to continue."""
    import recon.btf.exchange as exchange

    written = exchange.write_spectral_exr
    slices = iter(range(2))

    def interrupted_after_one(*args, **kwargs):
        if next(slices) == 1:
            raise KeyboardInterrupt
        return written(*args, **kwargs)

    monkeypatch.setattr(exchange, "write_spectral_exr", interrupted_after_one)
    out = inputs["RW"] / "interrupted_slices"
    result = runner.invoke(app, ["btf", "export", str(inputs["BTF"]), "--out", str(out), "--json"])
    assert result.exit_code == INTERRUPTED
    assert result.stderr.splitlines() == [
        f"interrupted: nothing was written to {out}; run the same command again"
    ]
    assert not out.exists()
    pairs = iter(range(2))
    write_pair = BTFStore.write_pair

    def write_one_pair(self, *args, **kwargs):
        if next(pairs) == 1:
            raise KeyboardInterrupt
        return write_pair(self, *args, **kwargs)

    monkeypatch.setattr(BTFStore, "write_pair", write_one_pair)
    out = inputs["RW"] / "interrupted.btf.zarr"
    result = runner.invoke(
        app, ["btf", "import", str(inputs["SLICES"]), "--out", str(out), "--json"]
    )
    assert result.exit_code == INTERRUPTED
    assert result.stderr.splitlines() == [
        f"interrupted: nothing was written to {out}; run the same command again"
    ]
    assert not out.exists() and not any(p.name.startswith(".") for p in inputs["RW"].iterdir())


def test_ctrl_c_in_the_demo_names_the_stage_and_how_to_start_over(inputs, monkeypatch):
    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("twin.studies.demo.run_gonio_calibration", interrupt)
    out = inputs["RW"] / "demo"
    result = runner.invoke(app, ["demo", "--out", str(out)])
    assert result.exit_code == INTERRUPTED
    assert result.stderr.splitlines() == [
        f"interrupted: in the demo's calibration session: {out} holds a part of the demo and "
        "no report; run the same command again to start it over"
    ]
    shutil.rmtree(out)


@pytest.mark.parametrize(
    ("pairs", "text"),
    [
        (range(156), "156 pairs: 0-155"),
        ([7], "1 pair: 7"),
        ([9, 1, 3, 4, 5, 10, 4], "6 pairs: 1, 3-5, 9-10"),
        ([0, 2, 4], "3 pairs: 0, 2, 4"),
    ],
)
def test_long_pair_lists_are_runs(pairs, text):
    from twin.output_format import format_pairs

    assert format_pairs(list(pairs)) == text


def _writing(path: str) -> typer.Typer:
    """A command group of one command that writes ``path``, with the errors of ``spectwin``."""
    group = typer.Typer(cls=SpectwinGroup)

    @group.command()
    def write() -> None:
        require_output_file(Path(path))
        Path(path).write_text("x" * 65536)

    @group.command()
    def other() -> None:
        """Keeps the group a group (a lone command would become the program itself)."""

    return group


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this system")
def test_a_full_disk_fails_the_run_in_one_line():
    result = runner.invoke(_writing("/dev/full"), ["write"])
    assert result.exit_code == 1
    assert result.stderr.splitlines() == [
        "error: No space left on device (writing --out /dev/full); free space on it"
    ]


def test_other_os_errors_keep_their_traceback(tmp_path):
    """A path that is not there (the command did not check it): a bug, not hidden."""
    result = runner.invoke(_writing(str(tmp_path / "absent" / "file")), ["write"])
    assert isinstance(result.exception, FileNotFoundError)
