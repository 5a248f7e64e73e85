"""A BTF store cannot lie (issue 42, items 1 and 2): every pair's reflectance chunk is sealed to
its place and the store, so a swapped, moved, foreign or reshaped chunk is found by name,
refused by readers and made pending again for a resumed run; the settings that define the store
(material, calibration, source, rig, texels, directions, wavelengths) are sealed at creation."""

import json

import numpy as np
import pytest

from recon.btf.store import BTFStore, write_btf
from recon.errors import DamagedDataError
from recon.spectra import DEFAULT_GRID

N_PAIRS, TEXELS = 4, 3
KEY, OTHER = "reflectance/c/3/0/0/0", "reflectance/c/1/0/0/0"
DIRECTIONS = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [0.8, 0.0, 0.6]])


def _store(path, *, seed=7, texels=TEXELS):
    rng = np.random.default_rng(seed)
    reflectance = rng.uniform(0.05, 0.9, (N_PAIRS, texels, texels, DEFAULT_GRID.size))
    write_btf(
        path,
        reflectance.astype(np.float32),
        DEFAULT_GRID,
        light_dirs=DIRECTIONS,
        view_dirs=DIRECTIONS[::-1],
        material="colorchecker16",
        calibration={"white": 0.99},
        source_capture="run.capture.zarr",
    )
    return path


@pytest.fixture(scope="module")
def donors(tmp_path_factory):
    root = tmp_path_factory.mktemp("donors")
    return {
        "foreign": _store(root / "foreign.btf.zarr", seed=8),
        "reshaped": _store(root / "reshaped.btf.zarr", texels=2),
    }


@pytest.fixture
def store(tmp_path):
    return _store(tmp_path / "cc.btf.zarr")


def test_a_misplaced_pair_chunk_is_named_refused_and_pending_again(store, donors, misplace):
    misplace(store, KEY, OTHER, donors)
    report = BTFStore.open(store).check()
    damaged = {problem.key for problem in report.problems}
    assert KEY in damaged and damaged <= {KEY, OTHER} and not report.healthy
    with pytest.raises(DamagedDataError, match=f"pair 3: {KEY} is") as refused:
        BTFStore.open(store).read_pair(3)
    assert "\n" not in str(refused.value)
    with pytest.raises(DamagedDataError, match="reflectance/c/"):
        BTFStore.open(store).read()
    resumed = BTFStore.open(store, writable=True)
    resumed.prepare_resume()
    assert 3 in resumed.pending_pairs()


def _set_shape(axis, value):
    return lambda metadata: metadata["shape"].__setitem__(axis, value)


@pytest.mark.parametrize(
    ("node", "edit", "named"),
    [
        ("zarr.json", lambda m: m["attributes"].update(material="wallpaper"), "material"),
        ("zarr.json", lambda m: m["attributes"]["calibration"].update(white=0.5), "calibration"),
        ("zarr.json", lambda m: m["attributes"].update(source_capture="b.zarr"), "source_capture"),
        ("zarr.json", lambda m: m["attributes"].update(rig="dome"), "rig"),
        ("reflectance/zarr.json", _set_shape(1, 2), "reflectance"),
        ("reflectance/zarr.json", _set_shape(0, 3), "reflectance"),
        ("written/zarr.json", _set_shape(0, 3), "written"),
    ],
    ids=["material", "calibration", "source", "rig", "texels", "pairs", "flags"],
)
def test_an_edited_setting_or_shape_is_refused_in_one_line(store, node, edit, named):
    metadata = json.loads((store / node).read_text())
    edit(metadata)
    (store / node).write_text(json.dumps(metadata))
    with pytest.raises(DamagedDataError) as refused:
        BTFStore.open(store)
    message = str(refused.value)
    assert named in message and str(store) in message and "\n" not in message


@pytest.mark.parametrize("array", ["light_dirs/c/0/0", "view_dirs/c/0/0", "wavelengths/c/0"])
def test_directions_or_wavelengths_from_another_store_are_refused(store, tmp_path, array):
    other = write_btf(
        tmp_path / "other.btf.zarr",
        np.full((N_PAIRS, TEXELS, TEXELS, 3), 0.5, np.float32),
        DEFAULT_GRID.__class__(np.array([450.0, 550.0, 650.0])),
        light_dirs=DIRECTIONS[::-1],
        view_dirs=DIRECTIONS,
        material="colorchecker16",
    ).path
    (store / array).write_bytes((other / array).read_bytes())
    with pytest.raises(DamagedDataError, match=array.split("/")[0]) as refused:
        BTFStore.open(store)
    assert "\n" not in str(refused.value)
