"""The local file store that reads and writes small files in place (hwbridge.local_store), against
Zarr's own LocalStore as its peer: the same files, the same values, atomic writes."""

import numpy as np
import pytest
import zarr
from zarr.abc.store import RangeByteRequest
from zarr.core.buffer import default_buffer_prototype
from zarr.core.sync import sync
from zarr.storage import LocalStore

from hwbridge.integrity import checksum_only, checksummed_compressors
from hwbridge.local_store import IN_PLACE_BYTES, LocalFileStore, open_local_group


def _write(group: zarr.Group, values: dict[str, np.ndarray]) -> None:
    for name, array in values.items():
        compressors = checksum_only() if array.ndim == 1 else checksummed_compressors()
        stored = group.create_array(
            name,
            shape=array.shape,
            chunks=(1, *array.shape[1:]),
            dtype=array.dtype,
            compressors=compressors,
        )
        stored[:] = array


def _files(folder) -> dict[str, bytes]:
    return {
        path.relative_to(folder).as_posix(): path.read_bytes()
        for path in folder.rglob("*")
        if path.is_file()
    }


VALUES = {
    "flags": np.array([True, False, True]),
    # Chunks of 128 x 128 float64 (128 KiB raw, above IN_PLACE_BYTES once compressed: noise).
    "frames": np.random.default_rng(0).normal(size=(2, 128, 128)),
}


def test_the_same_files_and_values_as_zarrs_local_store(tmp_path):
    _write(open_local_group(tmp_path / "ours.zarr", mode="w-"), VALUES)
    _write(zarr.open_group(store=LocalStore(tmp_path / "zarr.zarr"), mode="w-"), VALUES)
    ours, theirs = _files(tmp_path / "ours.zarr"), _files(tmp_path / "zarr.zarr")
    assert ours == theirs  # byte for byte, and no partial file left behind
    # Both ways were taken: the flags' chunks in place, the frames' (compressed noise) by Zarr.
    assert (
        len(ours["flags/c/0"])
        <= IN_PLACE_BYTES
        < min(len(ours[f"frames/c/{i}/0/0"]) for i in (0, 1))
    )
    for folder, store_class in (("ours.zarr", LocalFileStore), ("zarr.zarr", LocalStore)):
        for reader in (LocalFileStore, LocalStore):
            group = zarr.open_group(store=reader(tmp_path / folder, read_only=True), mode="r")
            for name, array in VALUES.items():
                np.testing.assert_array_equal(group[name][:], array, err_msg=f"{store_class}")


def test_missing_keys_ranges_and_read_only(tmp_path):
    store = LocalFileStore(tmp_path, read_only=False)
    prototype = default_buffer_prototype()
    assert sync(store.get("absent", prototype)) is None
    assert sync(store.get("absent/deeper", prototype)) is None
    sync(store.set("a/b", prototype.buffer.from_bytes(b"0123456789")))
    assert (tmp_path / "a" / "b").read_bytes() == b"0123456789"
    assert sync(store.get("a", prototype)) is None  # a folder is no value
    part = sync(store.get("a/b", prototype, RangeByteRequest(2, 5)))
    assert part is not None and part.to_bytes() == b"234"
    read_only = LocalFileStore(tmp_path, read_only=True)
    with pytest.raises(ValueError, match="read-only"):
        sync(read_only.set("a/c", prototype.buffer.from_bytes(b"x")))
    assert not (tmp_path / "a" / "c").exists()


def test_a_write_that_fails_leaves_the_old_file_and_no_partial_one(tmp_path, monkeypatch):
    store = LocalFileStore(tmp_path, read_only=False)
    prototype = default_buffer_prototype()
    sync(store.set("key", prototype.buffer.from_bytes(b"old")))

    def full_disk(*_args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("hwbridge.local_store.os.replace", full_disk)
    with pytest.raises(OSError, match="No space left"):
        sync(store.set("key", prototype.buffer.from_bytes(b"new")))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["key"]
    assert (tmp_path / "key").read_bytes() == b"old"
