"""A capture store cannot lie (issue 42, items 1 and 2): every frame chunk is sealed to its array,
its place and the store, so a swapped, moved, foreign or reshaped chunk is found by name, refused
by readers and taken again by a resumed simulated capture; and the settings that define the
store (plan, rig, seed, array shapes) are sealed at creation, so an edit is refused in one line."""

import json

import numpy as np
import pytest

from hwbridge.errors import DamagedDataError
from hwbridge.store import CaptureStore, FrameRecord

PLAN = [
    {"camera": "k4", "kind": "sample", "exposure_s": 0.5, "band_nm": 400.0 + 10 * i}
    for i in range(5)
]
SHAPE = (16, 12)
KEY, OTHER = "frames/k4/c/3/0/0", "frames/k4/c/1/0/0"


def _frame(seed, step, shape=SHAPE):
    return np.random.default_rng([seed, step]).integers(100, 4000, shape).astype(np.uint16)


def _store(path, *, seed=5, shape=SHAPE):
    store = CaptureStore.create(
        path,
        rig={"rig": "gonioreflectometer", "program": "test"},
        backend="sim",
        seed=seed,
        plan=PLAN,
        cameras={"k4": shape},
    )
    for step in range(len(PLAN)):
        store.write_frame(step, _frame(seed, step, shape), FrameRecord("sample", 0.5, 1.0))
        store.mark_done(step)
    return path


@pytest.fixture(scope="module")
def donors(tmp_path_factory):
    """A store like the tested one but of another seed, and one of smaller frames."""
    root = tmp_path_factory.mktemp("donors")
    return {
        "foreign": _store(root / "foreign.capture.zarr", seed=6),
        "reshaped": _store(root / "reshaped.capture.zarr", shape=(8, 12)),
    }


@pytest.fixture
def store(tmp_path):
    return _store(tmp_path / "run.capture.zarr")


def test_a_misplaced_frame_chunk_is_named_refused_and_taken_again(store, donors, misplace):
    misplace(store, KEY, OTHER, donors)
    report = CaptureStore.open(store).check()
    damaged = {problem.key for problem in report.problems}
    assert KEY in damaged and not report.healthy
    assert damaged <= {KEY, OTHER}  # a swap damages both places, nothing else is
    with pytest.raises(DamagedDataError, match=f"step 3 \\(frame 3\\): {KEY} is") as refused:
        CaptureStore.open(store).read_frames("k4", [3])
    assert "\n" not in str(refused.value)
    resumed = CaptureStore.open(store)
    assert 3 in {step for problem in resumed.prepare_resume() for step in problem.units}
    assert 3 in resumed.pending_steps()


@pytest.mark.parametrize(
    ("node", "edit", "named"),
    [
        ("zarr.json", lambda m: m["attributes"].update(seed=0), "seed"),
        ("zarr.json", lambda m: m["attributes"]["plan"][2].update(exposure_s=0.25), "plan"),
        ("zarr.json", lambda m: m["attributes"]["rig"].update(program="other"), "rig"),
        ("zarr.json", lambda m: m["attributes"].update(backend="real"), "backend"),
        ("frames/k4/zarr.json", lambda m: m["shape"].__setitem__(0, 4), "frames/k4"),
        ("frames/k4/zarr.json", lambda m: m["shape"].__setitem__(1, 8), "frames/k4"),
        ("index/k4/kind/zarr.json", lambda m: m["shape"].__setitem__(0, 4), "index/k4/kind"),
        ("progress/zarr.json", lambda m: m["shape"].__setitem__(0, 4), "progress"),
    ],
    ids=["seed", "plan", "rig", "backend", "frames", "frame-height", "index", "progress"],
)
def test_an_edited_setting_or_shape_is_refused_in_one_line(store, node, edit, named):
    metadata = json.loads((store / node).read_text())
    edit(metadata)
    (store / node).write_text(json.dumps(metadata))
    with pytest.raises(DamagedDataError) as refused:
        CaptureStore.open(store)
    message = str(refused.value)
    assert named in message and str(store) in message and "\n" not in message
