"""A BTF store through spectral EXR slices and back: bit-identical, and clear refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from recon.btf.exchange import INDEX_NAME, export_btf, import_exr_slices
from recon.btf.store import BTFStore, write_btf
from recon.errors import DamagedDataError, InputError
from recon.spectra import WavelengthGrid


def _directions(n_pairs: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    vectors = rng.normal(size=(n_pairs, 3))
    vectors[:, 2] = np.abs(vectors[:, 2])
    return vectors / np.linalg.norm(vectors, axis=1, keepdims=True)


@pytest.fixture
def store(tmp_path):
    """Six pairs of 5 x 7 texels on 9 irregular wavelengths, values with every kind of float32
    (tiny, huge, subnormal, negative zero), registered corners on some pairs."""
    rng = np.random.default_rng(4)
    values = rng.lognormal(-2, 2, (6, 5, 7, 9)).astype(np.float32)
    values[0, 0, 0, :4] = [np.float32(1e-42), np.float32(3e38), np.float32(-0.0), 0.1]
    grid = WavelengthGrid(np.array([400.0, 412.5, 430.0, 455.25, 500, 550, 600, 650, 700.1]))
    btf = write_btf(
        tmp_path / "source.btf.zarr",
        values,
        grid,
        light_dirs=_directions(6, 1),
        view_dirs=_directions(6, 2),
        material="wallpaper",
        calibration={"white": "spectralon", "exposure_s": [0.1, 0.25]},
    )
    writable = BTFStore.open(btf.path, writable=True)
    writable.write_pair(2, values[2], corners_xy=np.array([[1.5, 2.0], [9, 2], [9, 8], [1, 8]]))
    writable.set_attribute("unregistered_pairs", [4])
    return BTFStore.open(btf.path), values


def test_export_then_import_is_bit_identical(store, tmp_path):
    source, values = store
    index = export_btf(source, tmp_path / "slices")
    assert sorted(p.name for p in (tmp_path / "slices").iterdir()) == [
        INDEX_NAME,
        *(f"pair_{pair:05d}.exr" for pair in range(6)),
    ]
    assert json.loads(index.read_text())["pairs"][2]["corners_xy"][0] == [1.5, 2.0]
    copy = import_exr_slices(tmp_path / "slices", tmp_path / "copy.btf.zarr")
    assert copy.complete
    np.testing.assert_array_equal(copy.read().view(np.uint32), values.view(np.uint32))
    np.testing.assert_array_equal(copy.light_dirs, source.light_dirs)
    np.testing.assert_array_equal(copy.view_dirs, source.view_dirs)
    np.testing.assert_array_equal(copy.grid.wavelengths_nm, source.grid.wavelengths_nm)
    np.testing.assert_array_equal(copy.corners_xy(), source.corners_xy())  # NaN where none
    own = ("store_id", "sealed")  # a new store: its own identity and seals
    assert copy.attrs["store_id"] != source.attrs["store_id"]
    assert {k: v for k, v in copy.attrs.items() if k not in own} == {
        k: v for k, v in source.attrs.items() if k not in own
    }


def test_refusals_name_what_is_wrong(store, tmp_path):
    source, values = store
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "note.txt").write_text("mine")
    with pytest.raises(InputError, match="new or empty folder"):
        export_btf(source, tmp_path / "busy")
    partial = BTFStore.create(
        tmp_path / "partial.btf.zarr",
        light_dirs=source.light_dirs,
        view_dirs=source.view_dirs,
        texels=(5, 7),
        grid=source.grid,
        material="wallpaper",
    )
    partial.write_pair(0, values[0])
    with pytest.raises(InputError, match="incomplete BTF store"):
        export_btf(BTFStore.open(partial.path), tmp_path / "out")
    with pytest.raises(InputError, match=f"no {INDEX_NAME}"):
        import_exr_slices(tmp_path / "busy", tmp_path / "x.btf.zarr")
    export_btf(source, tmp_path / "slices")
    index_path = tmp_path / "slices" / INDEX_NAME
    index = json.loads(index_path.read_text())
    index["texels"] = [5, 8]
    index_path.write_text(json.dumps(index))
    with pytest.raises(DamagedDataError, match=r"pair_00000.exr: \(5, 7\) px .* expected \(5, 8\)"):
        import_exr_slices(tmp_path / "slices", tmp_path / "y.btf.zarr")
    index_path.write_text(json.dumps({**index, "texels": [5, 7], "units": "W/m2/sr"}))
    with pytest.raises(InputError, match="units 'W/m2/sr', expected '1/sr'"):
        import_exr_slices(tmp_path / "slices", tmp_path / "w.btf.zarr")
    index_path.write_text(json.dumps({**index, "format": "ubo2014"}))
    with pytest.raises(InputError, match="format 'ubo2014', expected"):
        import_exr_slices(tmp_path / "slices", tmp_path / "z.btf.zarr")
