"""Damaged stores at the command line: ``spectwin store check`` names the damage (exit 1),
``capture resume`` takes damaged simulated frames again, and ``process``, ``compress``,
``evaluate`` and ``validate`` refuse a damaged input in one line (exit 1) without writing.

The capture is the demo program (72 frames of 32 x 32 px, no render: about 8 s); the BTF is made
by hand (2 pairs of 16 x 16 texels).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

from hwbridge.schema import SCHEMA_VERSION
from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app

runner = CliRunner()


def _run(*arguments):
    return runner.invoke(app, [str(argument) for argument in arguments], prog_name="spectwin")


def _one_line_error(result, code: int) -> str:
    assert result.exit_code == code, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def _truncate(file: Path) -> None:
    file.write_bytes(file.read_bytes()[:9])


def _flip(file: Path) -> None:
    data = bytearray(file.read_bytes())
    data[len(data) // 2] ^= 0x01
    file.write_bytes(bytes(data))


def _swapped_with(place: str, other: str):
    """Swap a chunk file with the chunk at ``other`` in the path instead of ``place``."""

    def swap(file: Path) -> None:
        partner = Path(str(file).replace(place, other))
        data = file.read_bytes()
        file.write_bytes(partner.read_bytes())
        partner.write_bytes(data)

    return swap


def _copied_from(place: str, other: str):
    """Copy the chunk at ``other`` (in the path instead of ``place``) over a chunk file."""
    return lambda file: shutil.copyfile(str(file).replace(place, other), file)


def _edited(edit):
    """Edit a ``zarr.json`` file: ``edit(document)``."""

    def apply(file: Path) -> None:
        document = json.loads(file.read_text())
        edit(document)
        file.write_text(json.dumps(document))

    return apply


SEALED_ELSEWHERE = "is corrupt (sealed elsewhere"

# name: (file relative to the store, damage, what the error names)
CAPTURE_DAMAGE = {
    "moved chunk": ("frames/k4/c/40/0/0", _copied_from("/40/", "/41/"), SEALED_ELSEWHERE),
    "swapped chunks": ("frames/k4/c/40/0/0", _swapped_with("/40/", "/41/"), SEALED_ELSEWHERE),
    "edited seed": ("zarr.json", _edited(lambda m: m["attributes"].update(seed=5)), "seed differs"),
    "shrunk frames": (
        "frames/k4/zarr.json",
        _edited(lambda m: m["shape"].__setitem__(0, 71)),
        "frames/k4 differs",
    ),
    "deleted chunk": ("frames/k4/c/40/0/0", Path.unlink, "frames/k4/c/40/0/0 is missing"),
    "truncated chunk": ("frames/k4/c/40/0/0", _truncate, "frames/k4/c/40/0/0 is corrupt"),
    "flipped byte": ("frames/k4/c/40/0/0", _flip, "frames/k4/c/40/0/0 is corrupt"),
    "deleted root metadata": ("zarr.json", Path.unlink, "zarr.json is missing"),
    "deleted index metadata": ("index/k4/kind/zarr.json", Path.unlink, "kind/zarr.json is missing"),
    # A simulated capture keeps the flags of 1024 steps in one chunk: the demo's 72 are lost.
    "deleted progress flag": ("progress/c/0", Path.unlink, "progress flags of steps 0"),
}
CHUNKS = ("deleted chunk", "truncated chunk", "flipped byte", "moved chunk")
METADATA = ("deleted root metadata", "deleted index metadata", "edited seed", "shrunk frames")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("integrity")
    result = _run("capture", "demo", root / "demo.capture.zarr", "--json")
    assert result.exit_code == 0, result.output
    bands = DEFAULT_GRID.wavelengths_nm
    GonioCalibration.identity(np.full(bands.size, 2 / 15), bands, 1 / 15).save(root / "cal.json")
    directions = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)]])
    btf = BTFStore.create(
        root / "cc.btf.zarr",
        light_dirs=directions,
        view_dirs=directions[::-1],
        texels=16,
        grid=DEFAULT_GRID,
        material="colorchecker16",
        source_capture=root / "demo.capture.zarr",
    )
    for pair in range(2):
        btf.write_pair(pair, np.full((16, 16, DEFAULT_GRID.size), 0.2 + 0.1 * pair))
    return root


def _damaged_capture(inputs: Path, tmp_path: Path, damage: str) -> Path:
    store = tmp_path / "run.capture.zarr"
    shutil.copytree(inputs / "demo.capture.zarr", store)
    relative, action, _ = CAPTURE_DAMAGE[damage]
    action(store / relative)
    return store


def test_store_check_of_a_healthy_capture_prints_one_table_and_exits_0(inputs):
    result = _run("store", "check", inputs / "demo.capture.zarr")
    assert result.exit_code == 0 and result.stderr == ""
    for row in (
        "kind",
        "capture",
        "program",
        "demo",
        "seed",
        "verdict",
        "healthy",
        "pending steps",
        "missing chunks",
        "corrupt chunks",
        "checksums",
    ):
        assert row in result.stdout, row
    printed = json.loads(_run("store", "check", inputs / "demo.capture.zarr", "--json").stdout)
    assert printed["verdict"] == "healthy" and printed["complete"] is True
    assert (printed["steps"], printed["pending_steps"], printed["checksums"]) == (72, 0, "yes")
    assert (printed["program"], printed["seed"], printed["backend"]) == ("demo", 0, "sim")


@pytest.mark.parametrize("damage", CAPTURE_DAMAGE)
def test_store_check_names_the_damage_of_a_capture_and_exits_1(inputs, tmp_path, damage):
    store = _damaged_capture(inputs, tmp_path, damage)
    result = _run("store", "check", store, "--json")
    line = _one_line_error(result, 1)
    assert CAPTURE_DAMAGE[damage][2] in line
    if damage in CHUNKS:
        assert "camera k4 step 40 (frame 40)" in line
        printed = json.loads(result.stdout)
        assert printed["verdict"] == "damaged"
        assert printed["damaged"][0]["key"] == "frames/k4/c/40/0/0"
        count = "missing_chunks" if damage == "deleted chunk" else "corrupt_chunks"
        assert printed[count] == 1
    if damage == "deleted progress flag":
        assert json.loads(result.stdout)["pending_steps"] == 72


@pytest.mark.parametrize("damage", CAPTURE_DAMAGE)
def test_process_never_accepts_a_damaged_capture(inputs, tmp_path, damage):
    store = _damaged_capture(inputs, tmp_path, damage)
    out = tmp_path / "out.btf.zarr"
    result = _run("process", store, "--calibration", inputs / "cal.json", "--out", out)
    line = _one_line_error(result, 1)
    assert CAPTURE_DAMAGE[damage][2] in line
    assert not out.exists()


@pytest.mark.parametrize("damage", CAPTURE_DAMAGE)
def test_capture_resume_takes_damaged_simulated_frames_again(inputs, tmp_path, damage):
    store = _damaged_capture(inputs, tmp_path, damage)
    result = _run("capture", "resume", store, "--json")
    if damage in METADATA:
        assert CAPTURE_DAMAGE[damage][2] in _one_line_error(result, 1)
        return
    assert result.exit_code == 0, result.output
    if damage in CHUNKS:
        problem = "missing" if damage == "deleted chunk" else "corrupt"
        assert result.stdout.startswith(
            f"re-captured camera k4 step 40 (frame 40): frames/k4/c/40/0/0 was {problem}\n"
        )
    summary = json.loads(result.stdout[result.stdout.index("{") :])
    assert summary["complete"] is True
    recaptured = {"swapped chunks": 2, **dict.fromkeys(CHUNKS, 1)}
    assert summary["recaptured_frames"] == recaptured.get(damage, 0)
    assert _run("store", "check", store).exit_code == 0
    # The frame taken again is the frame of the uninterrupted capture, bit for bit.
    np.testing.assert_array_equal(
        CaptureStore.open(store).frames("k4")[:],
        CaptureStore.open(inputs / "demo.capture.zarr").frames("k4")[:],
    )


def test_process_refuses_an_incomplete_capture_naming_the_first_pending_step(inputs, tmp_path):
    store = tmp_path / "run.capture.zarr"
    shutil.copytree(inputs / "demo.capture.zarr", store)
    zarr.open_array(store / "progress", mode="r+")[[7, 9]] = False
    CaptureStore.open(store).prepare_resume()  # as an interrupted session leaves it
    out = tmp_path / "out.btf.zarr"
    result = _run("process", store, "--calibration", inputs / "cal.json", "--out", out)
    line = _one_line_error(result, 2)
    assert "the capture is incomplete (2 of 72 steps pending, first step 7)" in line
    assert _run("store", "check", store).exit_code == 0  # incomplete, not damaged
    same = _run("process", store, "--calibration", inputs / "cal.json", "--out", store)
    assert "is the capture store itself" in _one_line_error(same, 2)


BTF_DAMAGE = {
    "deleted chunk": ("reflectance/c/1/0/0/0", Path.unlink, "pair 1: reflectance/c/1/0/0/0 is"),
    "truncated chunk": ("reflectance/c/1/0/0/0", _truncate, "pair 1: reflectance/c/1/0/0/0 is"),
    "flipped byte": ("reflectance/c/1/0/0/0", _flip, "pair 1: reflectance/c/1/0/0/0 is corrupt"),
    "deleted root metadata": ("zarr.json", Path.unlink, "cc.btf.zarr/zarr.json is missing"),
    "deleted array metadata": ("reflectance/zarr.json", Path.unlink, "reflectance/zarr.json is"),
    "deleted written flag": ("written/c/1", Path.unlink, "progress flag of pair 1 is not set"),
    "swapped chunks": (
        "reflectance/c/1/0/0/0",
        _swapped_with("/c/1/", "/c/0/"),
        f"pair 0: reflectance/c/0/0/0/0 {SEALED_ELSEWHERE}",
    ),
    "edited material": (
        "zarr.json",
        _edited(lambda m: m["attributes"].update(material="wallpaper")),
        "material differs",
    ),
}


@pytest.fixture
def damaged_btf(inputs, tmp_path, request):
    store = tmp_path / "cc.btf.zarr"
    shutil.copytree(inputs / "cc.btf.zarr", store)
    relative, action, _ = BTF_DAMAGE[request.param]
    action(store / relative)
    return store, BTF_DAMAGE[request.param][2]


def test_store_check_of_a_healthy_btf_names_its_source_capture(inputs):
    printed = json.loads(_run("store", "check", inputs / "cc.btf.zarr", "--json").stdout)
    assert (printed["kind"], printed["verdict"], printed["pairs"]) == ("BTF", "healthy", 2)
    assert printed["source_capture"] == str(inputs / "demo.capture.zarr")
    assert (printed["program"], printed["seed"]) == ("demo", 0)


@pytest.mark.parametrize("damaged_btf", BTF_DAMAGE, indirect=True)
@pytest.mark.parametrize(
    "command",
    [
        ["store", "check"],
        ["compress"],
        ["evaluate"],
        ["validate", "--out", "@OUT"],
        ["validate", "--compressed", "--out", "@OUT"],
    ],
    ids=" ".join,
)
def test_commands_refuse_a_damaged_btf_in_one_line(damaged_btf, command, tmp_path):
    store, phrase = damaged_btf
    out = tmp_path / "validation"
    arguments = [command[0], *command[1:2], store] if command[0] == "store" else [command[0]]
    if command[0] != "store":
        arguments += [store] + [out if a == "@OUT" else a for a in command[1:]]
    line = _one_line_error(_run(*arguments), 1)
    assert phrase in line
    assert not out.exists()


def test_store_check_refuses_a_store_made_before_seals_in_one_line(tmp_path):
    import zarr

    path = tmp_path / "old.capture.zarr"
    group = zarr.open_group(str(path), mode="w-", zarr_format=3)
    group.attrs.update(
        {
            "schema_version": 1,
            "rig": {},
            "backend": "real",
            "seed": 3,
            "plan": [{"camera": "k4", "kind": "dark", "exposure_s": 0.1}],
            "complete": True,
        }
    )
    group.create_array("frames/k4", shape=(1, 4, 4), chunks=(1, 4, 4), dtype="uint16")[:] = 7
    for name, dtype, value in (("kind", str, "dark"), ("status", str, "ok")):
        group.create_array(f"index/k4/{name}", shape=(1,), dtype=dtype, fill_value="")[:] = value
    for name in ("light_id", "view_id", "band_nm", "exposure_s", "timestamp"):
        group.create_array(f"index/k4/{name}", shape=(1,), dtype="float64")[:] = 0.1
    group.create_array("index/k4/pose", shape=(1, 6), dtype="float64")
    group.create_array("progress", shape=(1,), dtype="bool")[:] = True
    line = _one_line_error(_run("store", "check", path), 2)
    assert f"schema version 1, expected {SCHEMA_VERSION}" in line


def test_a_capture_killed_after_its_last_frame_but_before_marking_complete_resumes_to_complete(
    inputs, tmp_path
):
    store = tmp_path / "run.capture.zarr"
    shutil.copytree(inputs / "demo.capture.zarr", store)
    zarr.open_group(str(store), mode="r+").attrs["complete"] = False  # every flag set, no mark
    assert not CaptureStore.open(store).complete and CaptureStore.open(store).pending_steps() == []
    result = _run("capture", "resume", store, "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout[result.stdout.index("{") :])["complete"] is True
    assert CaptureStore.open(store).complete
    np.testing.assert_array_equal(
        CaptureStore.open(store).frames("k4")[:],
        CaptureStore.open(inputs / "demo.capture.zarr").frames("k4")[:],
    )
