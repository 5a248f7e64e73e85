"""Integrity of the BTF store: checksums per chunk, the written flags checked against the
reflectance chunks, damaged metadata, and damaged pairs made pending again for a resumed run."""

import shutil

import numpy as np
import pytest

from recon.btf.compression import compress_btf, save_compressed
from recon.btf.store import BTFStore, write_btf
from recon.errors import DamagedDataError, InputError
from recon.spectra import DEFAULT_GRID

N_PAIRS, TEXELS = 4, 3


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    rng = np.random.default_rng(7)
    directions = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [0.8, 0.0, 0.6]])
    reflectance = rng.uniform(0.05, 0.9, (N_PAIRS, TEXELS, TEXELS, DEFAULT_GRID.size))
    path = tmp_path_factory.mktemp("pristine") / "cc.btf.zarr"
    write_btf(
        path,
        reflectance.astype(np.float32),
        DEFAULT_GRID,
        light_dirs=directions,
        view_dirs=directions[::-1],
        material="colorchecker16",
    )
    return path


@pytest.fixture
def store(pristine, tmp_path):
    path = tmp_path / "cc.btf.zarr"
    shutil.copytree(pristine, path)
    return path


def test_a_healthy_store_checks_clean_with_checksums(store):
    report = BTFStore.open(store).check()
    assert report.healthy and report.complete and report.checksums == "yes"
    assert (report.kind, report.unit, report.total) == ("BTF", "pair", N_PAIRS)
    assert report.provenance["material"] == "colorchecker16"


def test_a_damaged_pair_is_named_and_never_read_as_numbers(store, damage):
    damage(store / "reflectance/c/2/0/0/0")
    btf = BTFStore.open(store)
    report = btf.check()
    assert [(p.item, p.key, p.units) for p in report.problems] == [
        ("pair 2", "reflectance/c/2/0/0/0", (2,))
    ]
    assert report.problems[0].problem == ("missing" if damage.kind == "deleted" else "corrupt")
    # A deleted chunk would read as NaN, a flipped byte as other numbers: both raise instead.
    with pytest.raises(DamagedDataError, match="pair 2"):
        btf.read_pair(2)
    with pytest.raises(DamagedDataError, match="damaged store"):
        btf.read()
    with pytest.raises(DamagedDataError, match="damaged store"):
        list(btf.iter_pairs())
    np.testing.assert_array_equal(btf.read_pair(1), BTFStore.open(store).read_pair(1))


def test_a_resumed_run_finds_the_damaged_pairs_pending_again(store, damage):
    damage(store / "reflectance/c/1/0/0/0")
    btf = BTFStore.open(store, writable=True)
    assert [p.key for p in btf.prepare_resume()] == ["reflectance/c/1/0/0/0"]
    assert btf.pending_pairs() == [1] and not btf.complete
    assert not (store / "reflectance/c/1/0/0/0").exists()
    btf.write_pair(1, np.full((TEXELS, TEXELS, DEFAULT_GRID.size), 0.3))
    assert btf.complete and btf.check().healthy


def test_a_deleted_written_flag_contradicts_complete(store):
    (store / "written/c/3").unlink()
    report = BTFStore.open(store).check()
    assert report.pending == [3] and report.flags_disagree and not report.healthy
    assert report.damage() == "marked complete, but the progress flag of pair 3 is not set"


def test_a_corrupt_written_flag_is_named_and_the_pair_pending(store, chunk_damage):
    chunk_damage["flipped"](store / "written/c/0")
    btf = BTFStore.open(store)  # opening still works: check() can report
    report = btf.check()
    assert report.pending == [0] and report.problems[0].key == "written/c/0"
    with pytest.raises(DamagedDataError, match=r"pair 0 \(progress flag\): written/c/0 is corrupt"):
        btf.pending_pairs()


def test_a_damaged_compressed_form_is_reported_without_a_pair(store, chunk_damage):
    btf = BTFStore.open(store, writable=True)
    save_compressed(btf, compress_btf(btf.read(), btf.grid, n_brightness=2, n_spectral=3))
    chunk = next(path for path in sorted((store / "pca").rglob("c/*")) if path.is_file())
    chunk_damage["flipped"](chunk)
    report = BTFStore.open(store).check()
    assert [p.item for p in report.problems] == ["compressed form (pca/)"]
    assert report.problems[0].units == () and report.damaged_units == []
    with pytest.raises(DamagedDataError, match="compress again"):
        BTFStore.open(store).read_compressed()
    BTFStore.open(store, writable=True).prepare_resume()
    assert not BTFStore.open(store).has_compressed


@pytest.mark.parametrize(
    ("node", "error", "phrase"),
    [
        ("zarr.json", DamagedDataError, "the root metadata"),
        ("reflectance/zarr.json", DamagedDataError, "the metadata of reflectance"),
        ("light_dirs/zarr.json", DamagedDataError, "the metadata of light_dirs"),
        ("light_dirs/c/0/0", DamagedDataError, "light_dirs/c/0/0 is missing"),
        ("written/zarr.json", DamagedDataError, "the metadata of written"),
    ],
)
def test_damaged_metadata_is_one_line_naming_the_file(store, node, error, phrase):
    (store / node).unlink()
    with pytest.raises(error) as refused:
        BTFStore.open(store)
    assert phrase in str(refused.value) and "damaged store" in str(refused.value)
    assert "\n" not in str(refused.value)


def test_an_interrupted_creation_is_still_told_from_damage(tmp_path, store):
    shutil.rmtree(store / "written")  # created last: the creation stopped before it
    with pytest.raises(InputError, match="creation was interrupted"):
        BTFStore.open(store)
