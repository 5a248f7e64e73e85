"""``spectwin process --resume`` refuses inputs other than those the BTF store was made from, on
both rigs: another calibration file, another capture store, another ``--texels``. The BTF store
records the hash of each input at its creation; a refused resume writes nothing, and a resume
with the same inputs finishes the store.

The gonioreflectometer: two direction pairs at 96 px (about 2 s a capture); the dome: one
stage position, two LEDs, one RGB camera, 16 texels, 4 samples per pixel.
An interrupted processing is made by clearing the last pair's flag of a processed store, as a
run stopped before that pair leaves it.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app
from twin.gonio.capture import GonioPairs, run_gonio_measurement
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render
runner = CliRunner()
# 16 texels (the fewest processed) at 4 samples per pixel (the fewest rendered): the hashes and
# the refusals depend on neither; the calibration capture takes a sixth of its time at 32
# texels (measured on a loaded machine: 8 s, against 52 s at 32 texels and 4 spp).
DOME_SIZE = ["--leds", "2", "--rgb-cameras", "1", "--texels", "16", "--spp", "4"]


def _ok(*arguments) -> None:
    result = runner.invoke(app, [str(argument) for argument in arguments])
    assert result.exit_code == 0, result.output


def _gonio(root: Path) -> dict[str, Path]:
    bands = DEFAULT_GRID.wavelengths_nm
    calibration = GonioCalibration.identity(np.full(bands.size, 2 / 15), bands, 1 / 15)
    calibration.save(root / "cal.json")
    GonioCalibration.identity(0.65 * np.full(bands.size, 2 / 15), bands, 1 / 15).save(
        root / "other_cal.json"
    )
    pairs = GonioPairs(
        load_rig("gonio"),
        direction(np.array([30.0, 30.0]), np.array([0.0, 0.0])),
        direction(np.array([0.0, 30.0]), np.array([0.0, 135.0])),
    )
    for name, seed in (("run", 3), ("other_run", 4)):
        run_gonio_measurement(
            root / f"{name}.capture.zarr",
            calibration.planned_exposure_s,
            pairs=pairs,
            pixels=96,
            spp=4,
            seed=seed,
        )
    return {"texels": 16, "other_texels": 32, "calibration": root / "cal.json"}


def _dome(root: Path) -> dict[str, Path]:
    _ok("capture", "dome-calibration", root / "cal.capture.zarr", *DOME_SIZE, "--dark-frames", 2)
    _ok("calibrate", root / "cal.capture.zarr", "--out", root / "cal.npz", "--json")
    for name, seed in (("run", 3), ("other_run", 4)):
        run = root / f"{name}.capture.zarr"
        _ok("capture", "dome-run", run, *DOME_SIZE, "--stage-positions", 1, "--seed", seed)
    # Another calibration of the same rig: the spectral camera's response 0.65 times as steep.
    with np.load(root / "cal.npz") as saved:
        arrays = {name: saved[name] for name in saved.files}
    arrays["spectral_inverse_response"] = 0.65 * arrays["spectral_inverse_response"]
    with (root / "other_cal.npz").open("wb") as file:
        np.savez_compressed(file, **arrays)
    return {"texels": 16, "other_texels": 32, "calibration": root / "cal.npz"}


@pytest.fixture(scope="module", params=["gonio", "dome"])
def processed(request, tmp_path_factory) -> tuple[Path, dict]:
    """A rig's captures and calibrations, and a BTF store processed from the first of each."""
    root = tmp_path_factory.mktemp(request.param)
    rig = (_gonio if request.param == "gonio" else _dome)(root)
    _ok(
        "process",
        root / "run.capture.zarr",
        "--calibration",
        rig["calibration"],
        "--out",
        root / "run.btf.zarr",
        "--texels",
        rig["texels"],
        "--json",
    )
    return root, rig


@pytest.fixture
def interrupted(processed, tmp_path) -> tuple[Path, Path, dict]:
    """A copy of the processed store with its last pair pending again."""
    root, rig = processed
    btf = tmp_path / "run.btf.zarr"
    shutil.copytree(root / "run.btf.zarr", btf)
    group = zarr.open_group(btf, mode="r+")
    group["written"][-1] = False
    group.attrs["complete"] = False
    return root, btf, rig


def test_the_btf_store_records_the_hash_of_every_input(processed):
    from recon.btf.inputs import capture_sha256, file_sha256

    root, rig = processed
    inputs = BTFStore.open(root / "run.btf.zarr").metadata.inputs
    assert inputs is not None
    assert inputs.capture_sha256 == capture_sha256(CaptureStore.open(root / "run.capture.zarr"))
    assert inputs.calibration_sha256 == file_sha256(rig["calibration"])
    assert inputs.texels == rig["texels"]


# name: (the input that differs from the store's, what the one line names)
MISMATCHES = {
    "another calibration file": (
        lambda root, rig: {"calibration": root / f"other_cal{rig['calibration'].suffix}"},
        "another calibration file",
    ),
    "another capture store": (
        lambda root, rig: {"capture": root / "other_run.capture.zarr"},
        "another capture store",
    ),
    "other texels": (
        lambda root, rig: {"texels": rig["other_texels"]},
        "texels {other_texels}, the store has {texels}",
    ),
}


def _resume(root: Path, btf: Path, rig: dict, **changed) -> object:
    inputs = {"capture": root / "run.capture.zarr", "calibration": rig["calibration"]} | changed
    command = ["process", inputs["capture"], "--calibration", inputs["calibration"]]
    command += ["--out", btf, "--resume", "--json"]
    if "texels" in inputs:
        command += ["--texels", inputs["texels"]]
    return runner.invoke(app, [str(argument) for argument in command])


@pytest.mark.parametrize("mismatch", MISMATCHES)
def test_a_resume_with_other_inputs_is_refused_naming_the_difference(interrupted, mismatch):
    root, btf, rig = interrupted
    changed, named = MISMATCHES[mismatch]
    before = zarr.open_group(btf, mode="r")["written"][:]
    result = _resume(root, btf, rig, **changed(root, rig))
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert named.format(**rig) in lines[0]
    np.testing.assert_array_equal(zarr.open_group(btf, mode="r")["written"][:], before)
    assert not BTFStore.open(btf).complete


def test_a_resume_with_the_same_inputs_finishes_the_store(interrupted):
    root, btf, rig = interrupted
    result = _resume(root, btf, rig)
    assert result.exit_code == 0, result.output
    assert BTFStore.open(btf).complete


@pytest.mark.parametrize(
    ("option", "value", "name", "recorded"),
    [("--p-dyn", "0.5", "p_dyn", 0.0), ("--band-registration", "0", "band_registration", 0.25)],
)
def test_a_dome_resume_keeps_its_solve_options_and_the_gonio_takes_none(
    interrupted, option, value, name, recorded
):
    """The dome's ``--p-dyn`` (Eq. 10.2's exponent) and ``--band-registration`` are recorded
    with the BTF; a resume with another is refused in one line, writing nothing; the
    gonioreflectometer has neither and refuses the option."""
    root, btf, rig = interrupted
    command = ["process", root / "run.capture.zarr", "--calibration", rig["calibration"]]
    command += ["--out", btf, "--resume", "--texels", rig["texels"], option, value]
    result = runner.invoke(app, [str(argument) for argument in command])
    assert result.exit_code == 2, result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    if rig["calibration"].suffix == ".npz":
        assert BTFStore.open(btf).metadata.calibration[name] == recorded
        assert (
            f"begun with {name} {recorded:g}; a resumed processing keeps it, got {value}"
            in (lines[0])
        )
    else:
        assert f"{option} is not used by a gonioreflectometer run" in lines[0]
    assert not BTFStore.open(btf).complete
