"""The BTF store: round trip, incremental (resumable) assembly, incomplete stores, bad input."""

import numpy as np
import pytest
import zarr

from recon.btf.store import BTFStore, write_btf
from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, WavelengthGrid

N_PAIRS, HEIGHT, WIDTH = 6, 5, 4


def _hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    directions = rng.normal(size=(n, 3))
    directions[:, 2] = np.abs(directions[:, 2]) + 0.1
    return directions / np.linalg.norm(directions, axis=1, keepdims=True)


@pytest.fixture
def btf(rng):
    light_dirs, view_dirs = _hemisphere(rng, N_PAIRS), _hemisphere(rng, N_PAIRS)
    reflectance = rng.uniform(0.0, 2.0, (N_PAIRS, HEIGHT, WIDTH, DEFAULT_GRID.size))
    return reflectance.astype(np.float32), light_dirs, view_dirs


def _create(path, light_dirs, view_dirs, **options):
    return _create_with(path, light_dirs=light_dirs, view_dirs=view_dirs, **options)


def _create_with(path, **options):
    arguments = {
        "texels": (HEIGHT, WIDTH),
        "grid": DEFAULT_GRID,
        "material": "wallpaper",
    }
    return BTFStore.create(path, **{**arguments, **options})


def test_round_trip_keeps_values_directions_grid_and_provenance(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    path = tmp_path / "wallpaper.btf.zarr"
    calibration = {"white_reference": "spectralon", "exposure_s": [0.01, 0.1]}
    write_btf(
        path,
        reflectance,
        DEFAULT_GRID,
        light_dirs=light_dirs,
        view_dirs=view_dirs,
        material="wallpaper",
        source_capture="runs/wallpaper.capture.zarr",
        calibration=calibration,
    )
    store = BTFStore.open(path)
    assert store.complete and store.pending_pairs() == []
    assert store.shape == reflectance.shape and store.texels == (HEIGHT, WIDTH)
    assert store.grid == DEFAULT_GRID
    np.testing.assert_array_equal(store.read(), reflectance)
    np.testing.assert_array_equal(store.read_pair(3), reflectance[3])
    np.testing.assert_allclose(store.light_dirs, light_dirs, rtol=0, atol=0)
    np.testing.assert_allclose(store.view_dirs, view_dirs, rtol=0, atol=0)
    # Lazy access: the BRDF of one texel, and pair by pair.
    np.testing.assert_array_equal(store.reflectance()[:, 2, 1], reflectance[:, 2, 1])
    assert [pair for pair, _ in store.iter_pairs()] == list(range(N_PAIRS))
    attrs = store.attrs
    assert attrs["units"] == "1/sr" and attrs["material"] == "wallpaper"
    assert attrs["source_capture"] == "runs/wallpaper.capture.zarr"
    assert attrs["calibration"] == calibration
    chunks = zarr.open_group(str(path), mode="r")["reflectance"].chunks
    assert chunks == (1, HEIGHT, WIDTH, DEFAULT_GRID.size)  # one chunk per direction pair
    assert "complete" in repr(store)


def test_incremental_writes_resume_and_complete_only_at_the_last_pair(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    path = tmp_path / "assembled.btf.zarr"
    store = _create(path, light_dirs, view_dirs)
    assert not store.complete and store.pending_pairs() == list(range(N_PAIRS))
    for pair in (4, 0, 2):
        store.write_pair(
            pair,
            reflectance[pair],
            grid=DEFAULT_GRID,
            light_dir=light_dirs[pair],
            view_dir=view_dirs[pair],
        )
    assert store.pending_pairs() == [1, 3, 5] and not store.complete
    # Another session resumes the same store.
    resumed = BTFStore.open(path, writable=True)
    assert resumed.pending_pairs() == [1, 3, 5]
    partial = resumed.read(allow_incomplete=True)
    np.testing.assert_array_equal(partial[[0, 2, 4]], reflectance[[0, 2, 4]])
    assert np.all(np.isnan(partial[[1, 3, 5]]))
    for pair in resumed.pending_pairs():
        resumed.write_pair(pair, reflectance[pair])
        assert resumed.complete == (pair == 5)
    np.testing.assert_array_equal(BTFStore.open(path).read(), reflectance)
    # Redoing a pair is idempotent and leaves the store complete.
    resumed.write_pair(2, reflectance[2].astype(np.float64))
    assert resumed.complete
    np.testing.assert_array_equal(resumed.read(), reflectance)


def test_two_writers_owning_different_pairs_complete_the_store(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    path = tmp_path / "workers.btf.zarr"
    _create(path, light_dirs, view_dirs)
    first, second = BTFStore.open(path, writable=True), BTFStore.open(path, writable=True)
    for pair in range(0, N_PAIRS, 2):
        first.write_pair(pair, reflectance[pair])
    for pair in range(1, N_PAIRS, 2):
        second.write_pair(pair, reflectance[pair])
    assert second.complete and BTFStore.open(path).complete
    np.testing.assert_array_equal(first.read(), reflectance)


def test_interrupted_rewrite_leaves_the_pair_pending_not_complete(tmp_path, btf, monkeypatch):
    reflectance, light_dirs, view_dirs = btf
    path = tmp_path / "crash.btf.zarr"
    store = write_btf(
        path, reflectance, DEFAULT_GRID, light_dirs=light_dirs, view_dirs=view_dirs, material="m"
    )

    def crash(self):
        raise RuntimeError("power cut")

    monkeypatch.setattr(BTFStore, "_drop_compressed", crash)
    with pytest.raises(RuntimeError, match="power cut"):
        store.write_pair(1, reflectance[1] * 2)
    reopened = BTFStore.open(path)
    assert not reopened.complete and reopened.pending_pairs() == [1]
    with pytest.raises(InputError, match="incomplete"):
        reopened.read()


def test_incomplete_store_refuses_reads_unless_allowed(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    store = _create(tmp_path / "partial.btf.zarr", light_dirs, view_dirs)
    store.write_pair(0, reflectance[0])
    for read in (store.read, lambda: store.read_pair(0), store.reflectance):
        with pytest.raises(InputError, match=r"incomplete BTF store \(5 of 6 pairs"):
            read()
    with pytest.raises(InputError, match="incomplete"):
        list(store.iter_pairs())
    np.testing.assert_array_equal(store.read_pair(0, allow_incomplete=True), reflectance[0])
    with pytest.raises(InputError, match="pair 1 is not written"):
        store.read_pair(1, allow_incomplete=True)
    assert [pair for pair, _ in store.iter_pairs(allow_incomplete=True)] == [0]
    with pytest.raises(InputError, match="5 pairs pending"):
        store.mark_complete()
    with pytest.raises(InputError, match="incomplete"):
        store.write_compressed({"x": np.zeros(2)}, {})
    assert "5 pairs pending" in repr(store)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("light_dirs", np.tile([0.0, 0.0, 2.0], (N_PAIRS, 1)), r"light_dirs: expected unit"),
        ("view_dirs", np.tile([0.6, 0.0, 0.8], (N_PAIRS + 1, 1)), r"view_dirs: expected 6 dir"),
        ("view_dirs", np.tile([0.6, 0.0, -0.8], (N_PAIRS, 1)), r"view_dirs: .*above the sample"),
        ("light_dirs", np.full((N_PAIRS, 3), np.nan), r"light_dirs: expected finite"),
        ("light_dirs", np.zeros((N_PAIRS, 2)), r"light_dirs: expected an \(n_pairs, 3\)"),
        ("texels", (4, 0), r"texels: expected a positive int"),
        ("texels", 2.5, r"texels: expected a positive int"),
        ("grid", np.arange(400, 730, 10), r"grid: expected a WavelengthGrid"),
        ("material", "", r"material: expected a non-empty name"),
        ("calibration", {"when": object()}, r"calibration: expected JSON-serialisable"),
    ],
)
def test_create_rejects_bad_input(tmp_path, btf, field, value, message):
    _, light_dirs, view_dirs = btf
    options = {"light_dirs": light_dirs, "view_dirs": view_dirs, field: value}
    with pytest.raises(InputError, match=message):
        _create_with(tmp_path / "bad.btf.zarr", **options)
    assert not (tmp_path / "bad.btf.zarr").exists()


def test_create_never_overwrites(tmp_path, btf):
    _, light_dirs, view_dirs = btf
    path = tmp_path / "once.btf.zarr"
    _create(path, light_dirs, view_dirs)
    with pytest.raises(InputError, match="exists"):
        _create(path, light_dirs, view_dirs)


def test_write_pair_rejects_bad_input(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    path = tmp_path / "strict.btf.zarr"
    store = _create(path, light_dirs, view_dirs)
    texture = reflectance[0]
    with pytest.raises(InputError, match=r"pair: expected an index in 0..5, got 6"):
        store.write_pair(N_PAIRS, texture)
    with pytest.raises(InputError, match=r"pair: expected an index in 0..5, got -1"):
        store.write_pair(-1, texture)
    with pytest.raises(InputError, match="pair: expected an integer"):
        store.write_pair(1.0, texture)
    with pytest.raises(InputError, match=r"expected a texture of shape \(H, W, K\)"):
        store.write_pair(0, texture[..., :31])
    nan_texture = texture.copy()
    nan_texture[1, 2, 7] = np.nan
    with pytest.raises(InputError, match=r"NaN .* \(y, x, band\) = \(1, 2, 7\)"):
        store.write_pair(0, nan_texture)
    with pytest.raises(InputError, match="beyond float32"):
        store.write_pair(0, np.full(texture.shape, 1e300))
    other_grid = WavelengthGrid.regular(405, 725, 10)
    with pytest.raises(InputError, match="grid: the texture is on 33 samples, 405-725"):
        store.write_pair(0, texture, grid=other_grid)
    with pytest.raises(InputError, match="light_dir: pair 0 of the store"):
        store.write_pair(0, texture, light_dir=light_dirs[1])
    assert store.pending_pairs() == list(range(N_PAIRS))  # nothing was written
    with pytest.raises(InputError, match="opened read-only"):
        BTFStore.open(path).write_pair(0, texture)


def test_write_btf_and_open_reject_bad_input(tmp_path, btf):
    reflectance, light_dirs, view_dirs = btf
    with pytest.raises(InputError, match="does not match the grid"):
        write_btf(
            tmp_path / "a.btf.zarr",
            reflectance[..., :10],
            DEFAULT_GRID,
            light_dirs=light_dirs,
            view_dirs=view_dirs,
            material="m",
        )
    with pytest.raises(InputError, match="5 light directions"):
        write_btf(
            tmp_path / "a.btf.zarr",
            reflectance,
            DEFAULT_GRID,
            light_dirs=light_dirs[:5],
            view_dirs=view_dirs[:5],
            material="m",
        )
    with pytest.raises(InputError, match="does not exist"):
        BTFStore.open(tmp_path / "missing.btf.zarr")
    zarr.open_group(str(tmp_path / "other.zarr"), mode="w", zarr_format=3)
    with pytest.raises(InputError, match="not a BTF store"):
        BTFStore.open(tmp_path / "other.zarr")
    # A store whose creation stopped before its last array does not open.
    _create(tmp_path / "cut.btf.zarr", light_dirs, view_dirs)
    group = zarr.open_group(str(tmp_path / "cut.btf.zarr"), mode="r+")
    del group["written"]
    with pytest.raises(InputError, match=r"lacks arrays \['written'\]"):
        BTFStore.open(tmp_path / "cut.btf.zarr")
