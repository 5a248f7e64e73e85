"""The Zarr v3 capture store (hwbridge.store)."""

import numpy as np
import pytest
import zarr

from hwbridge.errors import InputError
from hwbridge.store import CaptureStore, FrameRecord

PLAN = [
    {"camera": "k4", "kind": "dark", "exposure_s": 0.5},
    {"camera": "rgb0", "kind": "sample", "exposure_s": 0.5},
    {"camera": "k4", "kind": "sample", "exposure_s": 0.5},
]
CAMERAS = {"k4": (8, 6), "rgb0": (4, 4)}


def _frame(shape, value):
    return np.full(shape, value, dtype=np.uint16)


def _new(tmp_path):
    return CaptureStore.create(
        tmp_path / "run.capture.zarr",
        rig={"rig": "gonioreflectometer"},
        backend="sim",
        seed=7,
        plan=PLAN,
        cameras=CAMERAS,
        monitor_samples=5,
    )


def test_frames_and_index_land_in_their_plan_slots(tmp_path):
    store = _new(tmp_path)
    store.write_frame(
        2,
        _frame((8, 6), 42),
        FrameRecord("sample", 0.5, 10.0, band_nm=550.0, lamp_monitor=np.ones(5)),
    )
    store.mark_done(2)
    assert store.pending_steps() == [0, 1] and not store.complete
    reopened = CaptureStore.open(tmp_path / "run.capture.zarr")
    assert reopened.frames("k4")[1].max() == 42 and reopened.frames("k4")[0].max() == 0
    index = reopened.index("k4")
    assert list(index["kind"]) == ["", "sample"] and index["band_nm"][1] == 550.0
    assert np.isnan(index["band_nm"][0]) and index["lamp_monitor"][1].sum() == 5
    # The layout is plain Zarr v3, readable without spectwin.
    group = zarr.open_group(str(tmp_path / "run.capture.zarr"), mode="r")
    assert (
        group.metadata.zarr_format == 3
        and group.attrs["seed"] == 7
        and group.attrs["backend"] == "sim"
    )


@pytest.mark.parametrize(("backend", "per_chunk", "level"), [("sim", 1024, 1), ("real", 1, 0)])
def test_a_simulated_capture_batches_its_index_and_compresses_frames_faster(
    tmp_path, backend, per_chunk, level
):
    """Simulated frames can be taken again: their index and flags share chunks of 1024 frames
    and frames get Zstd level 1; a real capture keeps one frame per chunk and Zstd's default."""
    plan = [{"camera": "k4", "kind": "sample", "exposure_s": 0.5}] * 2000
    store = CaptureStore.create(
        tmp_path / "run.capture.zarr",
        rig={},
        backend=backend,
        seed=0,
        plan=plan,
        cameras={"k4": (4, 4)},
    )
    store.write_frames(range(1020, 1030), [_frame((4, 4), step) for step in range(10)])
    store.write_index(range(1020, 1030), [FrameRecord("sample", 0.1, 0.0)] * 10)
    store.mark_done(range(1020, 1030))
    assert store.pending_steps() == [*range(1020), *range(1030, 2000)]
    assert (
        store.index("k4", ["kind"])["kind"][1018:1032].tolist()
        == [""] * 2 + ["sample"] * 10 + [""] * 2
    )
    assert [int(frame.max()) for frame in store.frames("k4")[1020:1030]] == list(range(10))
    group = zarr.open_group(str(tmp_path / "run.capture.zarr"), mode="r")
    assert group["index/k4/kind"].chunks == (per_chunk,) and group["progress"].chunks == (
        per_chunk,
    )
    assert group["frames/k4"].chunks == (1, 4, 4)
    assert group["frames/k4"].metadata.codecs[1].level == level  # bytes, then Zstd


def test_redoing_a_step_overwrites_instead_of_duplicating(tmp_path):
    store = _new(tmp_path)
    record = FrameRecord("dark", 0.1, 1.0)
    store.write_frame(0, _frame((8, 6), 5), record)
    store.write_frame(0, _frame((8, 6), 5), record)  # a crash before mark_done, then the redo
    for step, camera_shape in ((0, (8, 6)), (1, (4, 4)), (2, (8, 6))):
        store.write_frame(step, _frame(camera_shape, step + 1), FrameRecord("sample", 0.1, 2.0))
        store.mark_done(step)
    assert store.complete and store.frames("k4").shape == (2, 8, 6)
    assert [int(frame.max()) for frame in store.frames("k4")] == [1, 3]


def test_a_complete_stores_index_is_read_once_and_handed_out_as_copies(tmp_path, monkeypatch):
    """Calibrations select frames by their index many times over; a complete store reads each
    field once. Each caller gets its own copy, and writing the index again is read again."""
    store = _new(tmp_path)
    for step, camera in enumerate(step["camera"] for step in PLAN):
        store.write_frame(step, _frame(CAMERAS[camera], step), FrameRecord("sample", 0.1, 2.0))
        store.mark_done(step)
    assert store.complete
    reads = []
    read = CaptureStore._read
    monkeypatch.setattr(
        CaptureStore, "_read", lambda self, array: reads.append(1) or read(self, array)
    )
    first = store.index("k4", ["kind", "exposure_s"])
    first["exposure_s"][:] = -1.0  # the caller's copy
    second = store.index("k4", ["kind", "exposure_s"])
    assert len(reads) == 2 and second["exposure_s"].tolist() == [0.1, 0.1]
    store.write_frame(2, _frame((8, 6), 9), FrameRecord("dark", 0.5, 3.0))
    assert store.index("k4", ["exposure_s"])["exposure_s"].tolist() == [0.1, 0.5]
    assert len(reads) == 3


def test_bad_input_is_refused_and_nothing_is_overwritten(tmp_path):
    store = _new(tmp_path)
    store.write_frame(0, _frame((8, 6), 9), FrameRecord("dark", 0.1, 1.0))
    with pytest.raises(InputError, match="exists"):
        _new(tmp_path)
    assert CaptureStore.open(tmp_path / "run.capture.zarr").frames("k4")[0].max() == 9
    with pytest.raises(InputError, match="uint16"):
        store.write_frame(0, np.zeros((8, 6)), FrameRecord("dark", 0.1, 1.0))
    with pytest.raises(InputError, match="step"):
        store.mark_done(3)
    with pytest.raises(InputError, match="kind"):
        FrameRecord("selfie", 0.1, 1.0)
    with pytest.raises(InputError, match="exposure_s"):
        FrameRecord("dark", -1.0, 1.0)
    with pytest.raises(InputError, match="not among"):
        CaptureStore.create(
            tmp_path / "other.zarr",
            rig={},
            backend="sim",
            seed=0,
            plan=[{"camera": "x", "kind": "dark", "exposure_s": 0.5}],
            cameras=CAMERAS,
        )
    with pytest.raises(InputError, match="backend"):
        CaptureStore.create(
            tmp_path / "b.zarr", rig={}, backend="dream", seed=0, plan=PLAN, cameras=CAMERAS
        )


def test_a_creation_that_fails_midway_leaves_no_store_behind(tmp_path):
    path = tmp_path / "run.capture.zarr"
    # A camera whose frame shape zarr refuses fails after the plan was already written.
    with pytest.raises(Exception):  # noqa: B017 (whatever zarr raises for a negative shape)
        CaptureStore.create(
            path,
            rig={"rig": "gonioreflectometer"},
            backend="sim",
            seed=7,
            plan=PLAN,
            cameras={"k4": (8, 6), "rgb0": (-4, 4)},
        )
    assert not path.exists()  # so a resume cannot meet a store without progress
    store = _new(tmp_path)  # the same name can be created afresh
    assert store.pending_steps() == [0, 1, 2]
