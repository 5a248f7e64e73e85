"""``spectwin btf export`` and ``spectwin btf import`` at the command line: a round trip that
keeps every bit, and one-line refusals (a BTF store made by hand: 3 pairs of 6 x 6 texels).

The import checks its input before it writes and writes atomically: every defect of an exported
folder (its index, its attributes, its slices, 4 pairs on 5 bands), of a UBO2014 header and of
an RGB image folder is refused in one line, and the failed import leaves nothing at ``--out``
(nor a temporary store beside it), so the same ``--out`` takes a good import afterwards."""

from __future__ import annotations

import json
import shutil
import struct
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from recon.btf.exchange import INDEX_NAME, export_btf
from recon.btf.rgb_import import DIRECTION_TABLE, RGB_COLUMNS
from recon.btf.store import BTFStore, write_btf
from recon.spectra import DEFAULT_GRID, WavelengthGrid
from recon.spectral_exr import read_spectral_exr, write_spectral_exr
from twin.cli.app import app

runner = CliRunner()


def _run(*arguments):
    return runner.invoke(app, [str(argument) for argument in arguments], prog_name="spectwin")


def _one_line_error(result, code: int) -> str:
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def _made_btf(path: Path, pairs: int, grid: WavelengthGrid) -> tuple[BTFStore, np.ndarray]:
    """A BTF store of ``pairs`` random textures of 6 x 6 texels on ``grid``, and its values."""
    values = np.random.default_rng(0).random((pairs, 6, 6, grid.size), np.float32)
    directions = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [0.6, 0.0, 0.8]])
    source = write_btf(
        path,
        values,
        grid,
        light_dirs=directions[:pairs],
        view_dirs=directions[:pairs][::-1],
        material="lego",
    )
    return source, values


def test_export_and_import_round_trip_and_refusals(tmp_path):
    source, values = _made_btf(tmp_path / "a.btf.zarr", 3, DEFAULT_GRID)
    exported = _run("btf", "export", source.path, "--out", tmp_path / "slices", "--json")
    assert exported.exit_code == 0, exported.output
    assert json.loads(exported.stdout)["pairs"] == 3
    imported = _run(
        "btf", "import", tmp_path / "slices", "--out", tmp_path / "b.btf.zarr", "--json"
    )
    assert imported.exit_code == 0, imported.output
    assert json.loads(imported.stdout)["complete"] is True
    copy = BTFStore.open(tmp_path / "b.btf.zarr")
    np.testing.assert_array_equal(copy.read().view(np.uint32), values.view(np.uint32))
    assert copy.material == "lego"

    again = _run("btf", "import", tmp_path / "slices", "--out", tmp_path / "b.btf.zarr")
    assert "exists" in _one_line_error(again, 2)
    busy = _run("btf", "export", source.path, "--out", tmp_path / "slices")
    assert "new or empty folder" in _one_line_error(busy, 2)
    empty = tmp_path / "empty"
    empty.mkdir()
    missing = _run("btf", "import", empty, "--out", tmp_path / "c.btf.zarr")
    assert "no directions.json" in _one_line_error(missing, 2)
    assert not (tmp_path / "c.btf.zarr").exists()


GRID = WavelengthGrid(np.array([450.0, 500, 550, 600, 650]))


@pytest.fixture(scope="module")
def slices(tmp_path_factory) -> Path:
    """An export of 4 pairs on 5 bands."""
    root = tmp_path_factory.mktemp("slices")
    btf, _ = _made_btf(root / "a.btf.zarr", 4, GRID)
    return export_btf(BTFStore.open(btf.path), root / "slices").parent


def _edit_index(edit: Callable[[dict], None]) -> Callable[[Path], Path]:
    def damage(folder: Path) -> Path:
        index = json.loads((folder / INDEX_NAME).read_text())
        edit(index)
        (folder / INDEX_NAME).write_text(json.dumps(index))
        return folder

    return damage


def _rewrite_slice(pair: int, change: Callable[[np.ndarray], np.ndarray], kind="reflective"):
    def damage(folder: Path) -> Path:
        path = folder / f"pair_{pair:05d}.exr"
        image = read_spectral_exr(path)
        write_spectral_exr(path, change(image.cube), image.grid, kind=kind)
        return folder

    return damage


def _with_nan(cube: np.ndarray) -> np.ndarray:
    cube = cube.copy()
    cube[2, 3, 1] = np.nan
    return cube


def _both(*damages: Callable[[Path], Path]) -> Callable[[Path], Path]:
    def damage(folder: Path) -> Path:
        for one in damages:
            one(folder)
        return folder

    return damage


def _outside(folder: Path) -> Path:
    shutil.copy(folder / "pair_00001.exr", folder.parent / "elsewhere.exr")
    return _edit_index(lambda index: index["pairs"][0].update(file="../elsewhere.exr"))(folder)


def _truncated(folder: Path) -> Path:
    path = folder / "pair_00003.exr"
    path.write_bytes(path.read_bytes()[:100])
    return folder


def _slices_claiming_60000_texels(folder: Path) -> Path:
    """The index and every slice's header (its data window) claim 60000 x 60000 texels; the
    files keep their 6 x 6 pixels."""
    _edit_index(lambda index: index.update(texels=[60000, 60000]))(folder)
    window = b"dataWindow\x00box2i\x00" + struct.pack("<i", 16)
    for path in folder.glob("pair_*.exr"):
        data = path.read_bytes()
        start = data.index(window) + len(window)
        path.write_bytes(data[:start] + struct.pack("<4i", 0, 0, 59999, 59999) + data[start + 16 :])
    return folder


def _ubo2014_claiming_60000_texels(folder: Path) -> Path:
    """A 408-byte UBO2014 file: one direction, a 60000 x 60000 texture and factors of no
    component, which decode to 13.4 GiB per channel."""
    header = struct.pack("<II", 264, 1) + bytes(240) + struct.pack("<4f", 1, 1, 1, 1)
    directions = struct.pack("<I2fI2f", 1, 0, 0, 1, 0, 0)
    factors = struct.pack("<II", 0, 0) + bytes(48)
    channel = struct.pack("<BIII", 2, 0, 1, 60000 * 60000)
    path = folder.parent / "huge.btf"
    path.write_bytes(
        b"!DFMF08FC"
        + header
        + directions
        + struct.pack("<II", 60000, 60000)
        + factors
        + channel * 3
    )
    return path


def _rgb_image_of_another_size(folder: Path) -> Path:
    images = folder.parent / "images"
    images.mkdir()
    rows = [",".join(RGB_COLUMNS)]
    for number, size in enumerate((8, 8, 8, 6)):
        cv2.imwrite(str(images / f"{number}.png"), np.full((size, size, 3), 40 * number, np.uint8))
        rows.append(f"{number}.png,{10 * number},0,0,0")
    (images / DIRECTION_TABLE).write_text("\n".join(rows) + "\n")
    return images


# name: (damage of a copy of the exported folder, returning the source to import; exit code;
# what the one line says)
DEFECTS = {
    "index sets the store's format": (
        _edit_index(lambda index: index["attributes"].update(format="other")),
        2,
        "attributes ['format'] are the BTF store's own",
    ),
    "index says complete, one slice bad": (
        _both(
            _edit_index(lambda index: index["attributes"].update(complete=True)),
            _rewrite_slice(2, _with_nan),
        ),
        2,
        "attributes ['complete'] are the BTF store's own",
    ),
    "index has an unknown attribute": (
        _edit_index(lambda index: index["attributes"].update(colour="red")),
        2,
        "attributes: colour: Extra inputs are not permitted",
    ),
    "index texels not numbers": (
        _edit_index(lambda index: index.update(texels=["six", 6])),
        2,
        "texels.0: Input should be a valid integer",
    ),
    "slice outside the folder": (_outside, 2, "pairs.0.file: String should match pattern"),
    "emissive slice": (
        _rewrite_slice(1, lambda cube: cube, kind="emissive"),
        2,
        "emissive (S0) channels hold radiance",
    ),
    "slice of another size": (
        _rewrite_slice(3, lambda cube: cube[:5]),
        1,
        "pair_00003.exr: (5, 6) px",
    ),
    "truncated slice": (_truncated, 1, "pair_00003.exr: not a readable EXR"),
    "slice headers claiming 60000 x 60000 texels": (
        _slices_claiming_60000_texels,
        1,
        "bytes cannot hold (60000, 60000) px x 5 channels",
    ),
    "NaN in a slice": (_rewrite_slice(2, _with_nan), 2, "found NaN or infinity"),
    "UBO2014 header claiming 60000 x 60000 texels": (
        _ubo2014_claiming_60000_texels,
        2,
        "channel 0 has 0 components; expected 1 to 1",
    ),
    "RGB image of another size mid-import": (
        _rgb_image_of_another_size,
        2,
        "3.png is 6 x 6 px, expected 8 x 8",
    ),
}


@pytest.mark.parametrize("defect", DEFECTS)
def test_a_defective_import_is_refused_in_one_line_and_leaves_nothing(slices, tmp_path, defect):
    damage, code, message = DEFECTS[defect]
    folder = tmp_path / "slices"
    shutil.copytree(slices, folder)
    source = damage(folder)
    out = tmp_path / "out" / "copy.btf.zarr"
    out.parent.mkdir()
    result = runner.invoke(app, ["btf", "import", str(source), "--out", str(out), "--json"])
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert message in lines[0]
    assert list(out.parent.iterdir()) == []  # neither the store nor a temporary one
    good = runner.invoke(app, ["btf", "import", str(slices), "--out", str(out), "--json"])
    assert good.exit_code == 0, good.output
    assert BTFStore.open(out).complete
