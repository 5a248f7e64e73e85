"""Integrity of the capture store (hwbridge.store, hwbridge.integrity): checksums per chunk, the
progress record checked against the chunks, damaged metadata, and what a resumed session does
with damage (takes simulated frames again, refuses real and replayed ones)."""

import json
import shutil

import numpy as np
import pytest
import zarr

from hwbridge.errors import DamagedDataError, InputError
from hwbridge.integrity import has_checksums
from hwbridge.schema import SCHEMA_VERSION
from hwbridge.session import SessionDevices, SessionSettings, run_session
from hwbridge.store import CaptureStore, FrameRecord

PLAN = [{"camera": "k4", "kind": "dark", "exposure_s": 0.1}] + [
    {"camera": "k4", "kind": "sample", "exposure_s": 0.5, "band_nm": 400.0 + 10 * i}
    for i in range(4)
]
SHAPE = (16, 12)


class Filter:
    band_nm = None

    def set(self, band_nm):
        self.band_nm = band_nm


class StepCamera:
    """A camera whose frame is a function of the step, like the simulated ones; it tells the
    step from the band its filter is tuned to (none: the dark frame)."""

    frame_shape = SHAPE

    def __init__(self, tunable_filter):
        self.snaps, self._filter = [], tunable_filter

    def set_exposure(self, exposure_s):
        self.exposure_s = exposure_s

    def snap(self):
        bands = [step.get("band_nm") for step in PLAN]
        step = bands.index(self._filter.band_nm)
        self.snaps.append(step)
        values = np.random.default_rng([5, step]).integers(100, 4000, SHAPE)
        return values.astype(np.uint16), {"timestamp": 1.0}


def _devices():
    tunable_filter = Filter()
    return SessionDevices(cameras={"k4": StepCamera(tunable_filter)}, tunable_filter=tunable_filter)


def _capture(path, backend="sim"):
    settings = SessionSettings(
        rig={"rig": "gonioreflectometer", "program": "test"},
        backend=backend,
        seed=5,
        show_progress=False,
    )
    return run_session(path, PLAN, _devices(), settings)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A complete store of 5 steps, copied by each test that damages it."""
    return _capture(tmp_path_factory.mktemp("pristine") / "run.capture.zarr").path


@pytest.fixture
def store(pristine, tmp_path):
    path = tmp_path / "run.capture.zarr"
    shutil.copytree(pristine, path)
    return path


def test_a_healthy_store_has_checksums_on_every_array_and_reports_its_provenance(store):
    report = CaptureStore.open(store).check()
    assert report.healthy and report.complete and report.problems == []
    assert report.checksums == "yes" and report.damage() is None
    assert report.provenance == {"backend": "sim", "program": "test", "seed": 5}
    group = zarr.open_group(str(store), mode="r")
    arrays = [group["frames/k4"], group["progress"], *group["index/k4"].array_values()]
    assert all(has_checksums(array) for array in arrays)


def test_a_damaged_frame_chunk_is_named_by_camera_step_and_key(store, damage):
    damage(store / "frames/k4/c/3/0/0")
    capture = CaptureStore.open(store)
    report = capture.check()
    assert not report.healthy and report.damaged_units == [3]
    (problem,) = report.problems
    assert problem.item == "camera k4 step 3 (frame 3)"
    assert problem.key == "frames/k4/c/3/0/0"
    assert problem.problem == ("missing" if damage.kind == "deleted" else "corrupt")
    assert report.damage().startswith("camera k4 step 3 (frame 3): frames/k4/c/3/0/0 is ")
    # Zarr alone would return zeros for the deleted chunk; reading through the store refuses.
    with pytest.raises(DamagedDataError, match=r"camera k4 step 3 \(frame 3\): frames/k4/c/3/0/0"):
        capture.read_frames("k4", [2, 3])
    np.testing.assert_array_equal(
        capture.read_frames("k4", [2])[0], capture.frames("k4")[2]
    )  # the sound frames still read
    if damage.kind == "deleted":
        assert not capture.check(verify=False).healthy  # presence alone finds it
    else:
        assert capture.check(verify=False).healthy  # only the checksums find it


def test_a_damaged_index_chunk_of_done_steps_is_found(store, damage):
    # A simulated capture keeps the index of INDEX_CHUNK_FRAMES frames in one chunk: all five.
    damage(store / "index/k4/exposure_s/c/0")
    report = CaptureStore.open(store).check()
    assert [(p.item, p.key, p.units) for p in report.problems] == [
        ("camera k4 step 0 (frame 0)", "index/k4/exposure_s/c/0", (0, 1, 2, 3, 4))
    ]
    if damage.kind == "deleted":  # Zarr reads the fill value: only the check sees it
        assert np.isnan(CaptureStore.open(store).index("k4", ["exposure_s"])["exposure_s"]).all()
    else:
        with pytest.raises(DamagedDataError, match="index/k4/exposure_s cannot be read"):
            CaptureStore.open(store).index("k4")


def test_a_damaged_index_chunk_of_a_real_capture_costs_one_frame(tmp_path, damage):
    path = _capture(tmp_path / "run.capture.zarr", backend="real").path
    damage(path / "index/k4/exposure_s/c/2")
    report = CaptureStore.open(path).check()
    assert [(p.item, p.key, p.units) for p in report.problems] == [
        ("camera k4 step 2 (frame 2)", "index/k4/exposure_s/c/2", (2,))
    ]


def test_resuming_a_simulated_capture_takes_the_damaged_frames_again(store, pristine, damage):
    damage(store / "frames/k4/c/1/0/0")
    damage(store / "frames/k4/c/4/0/0")
    devices = _devices()
    settings = SessionSettings(rig={}, backend="sim", seed=5, resume=True, show_progress=False)
    resumed = run_session(store, PLAN, devices, settings)
    assert devices.cameras["k4"].snaps == [1, 4]  # only the damaged steps were taken again
    assert [p.key for p in resumed.recaptured] == ["frames/k4/c/1/0/0", "frames/k4/c/4/0/0"]
    assert resumed.complete and CaptureStore.open(store).check().healthy
    np.testing.assert_array_equal(
        resumed.frames("k4")[:], CaptureStore.open(pristine).frames("k4")[:]
    )


@pytest.mark.parametrize("backend", ["real", "replay"])
def test_resuming_a_real_or_replayed_capture_with_damaged_frames_is_refused(
    tmp_path, backend, damage
):
    path = _capture(tmp_path / "run.capture.zarr", backend=backend).path
    damage(path / "frames/k4/c/2/0/0")
    damage(path / "frames/k4/c/3/0/0")
    devices = _devices()
    settings = SessionSettings(rig={}, backend=backend, seed=5, resume=True, show_progress=False)
    with pytest.raises(DamagedDataError) as refused:
        run_session(path, PLAN, devices, settings)
    message = str(refused.value)
    assert "camera k4 step 2 (frame 2): frames/k4/c/2/0/0 is" in message
    assert f"a {backend} capture cannot take its frames again" in message
    assert "\n" not in message and devices.cameras["k4"].snaps == []
    assert CaptureStore.open(path).pending_steps() == []  # nothing was changed


@pytest.mark.parametrize("backend", ["sim", "real"])
def test_a_deleted_progress_chunk_makes_its_steps_pending_and_contradicts_complete(
    tmp_path, backend
):
    path = _capture(tmp_path / "run.capture.zarr", backend=backend).path
    lost = [0, 1, 2, 3, 4] if backend == "sim" else [2]  # flags per chunk: 1024 or 1
    (path / f"progress/c/{lost[0]}").unlink()
    capture = CaptureStore.open(path)
    report = capture.check()
    assert report.pending == lost and report.flags_disagree and not report.healthy
    assert report.problems == [] and capture.complete  # the attribute alone still says so
    plural = "s" * (len(lost) > 1)
    assert report.damage().startswith(f"marked complete, but the progress flag{plural} of step")
    capture.prepare_resume()
    assert not capture.complete and capture.pending_steps() == lost


@pytest.mark.parametrize("backend", ["sim", "real"])
def test_a_corrupt_progress_chunk_only_makes_its_steps_pending(tmp_path, backend, chunk_damage):
    path = _capture(tmp_path / "run.capture.zarr", backend=backend).path
    chunk = 0 if backend == "sim" else 1
    lost = [0, 1, 2, 3, 4] if backend == "sim" else [1]
    chunk_damage["flipped"](path / f"progress/c/{chunk}")
    capture = CaptureStore.open(path)
    report = capture.check()
    assert report.pending == lost
    assert [(p.item, p.problem) for p in report.problems] == [
        (f"camera k4 step {lost[0]} (frame {lost[0]}) (progress flag)", "corrupt")
    ]
    with pytest.raises(
        DamagedDataError, match=rf"progress/c/{chunk} is corrupt \(checksum mismatch\)"
    ):
        capture.pending_steps()
    assert [p.key for p in capture.prepare_resume()] == [f"progress/c/{chunk}"]  # any backend
    assert capture.pending_steps() == lost and not capture.complete


def test_a_frame_of_zeros_is_written_and_not_taken_for_a_missing_chunk(tmp_path):
    capture = CaptureStore.create(
        tmp_path / "zeros.capture.zarr",
        rig={},
        backend="sim",
        seed=0,
        plan=PLAN[:1],
        cameras={"k4": SHAPE},
    )
    capture.write_frame(0, np.zeros(SHAPE, np.uint16), FrameRecord("dark", 0.1, 0.0))
    capture.mark_done(0)
    assert (capture.path / "frames/k4/c/0/0/0").is_file() and capture.check().healthy


@pytest.mark.parametrize(
    ("node", "what"),
    [
        ("zarr.json", "the root metadata"),
        ("index/k4/kind/zarr.json", "the metadata of index/k4/kind"),
        ("index/k4/zarr.json", "the metadata of index/k4"),
        ("frames/k4/zarr.json", "the metadata of frames/k4"),
        ("progress/zarr.json", "the metadata of progress"),
    ],
)
@pytest.mark.parametrize("damage", ["deleted", "unreadable"])
def test_damaged_metadata_is_one_line_naming_the_file(store, node, what, damage):
    file = store / node
    if damage == "deleted":
        file.unlink()
    else:
        file.write_text(file.read_text()[:40])
    with pytest.raises(DamagedDataError) as refused:
        CaptureStore.open(store)
    message = str(refused.value)
    expected = "is missing" if damage == "deleted" else "is unreadable"
    assert f"{file} {expected}" in message and what in message and "\n" not in message


def _old_store(path):
    """A store laid out as before checksums and seals (schema version 1): Zarr's default codecs,
    ``kind`` and ``status`` in one chunk per camera (the oldest layout), frames one chunk
    each."""
    group = zarr.open_group(str(path), mode="w-", zarr_format=3)
    plan = PLAN[:3]
    group.attrs.update(
        {
            "schema_version": 1,
            "rig": {},
            "backend": "sim",
            "seed": 1,
            "plan": plan,
            "complete": True,
        }
    )
    frames = group.create_array("frames/k4", shape=(3, *SHAPE), chunks=(1, *SHAPE), dtype="uint16")
    frames[:] = np.arange(1, 4, dtype=np.uint16)[:, None, None] * 100
    for name in ("kind", "status"):
        values = [step["kind"] for step in plan] if name == "kind" else ["ok"] * 3
        group.create_array(f"index/k4/{name}", shape=(3,), chunks=(3,), dtype=str, fill_value="")[
            :
        ] = values
    numeric = {"light_id": -1, "view_id": -1, "band_nm": np.nan, "exposure_s": np.nan}
    for name, fill in {**numeric, "timestamp": np.nan}.items():
        array = group.create_array(
            f"index/k4/{name}",
            shape=(3,),
            chunks=(1,),
            dtype="float64" if np.isnan(fill) else "int32",
            fill_value=fill,
        )
        if name in ("exposure_s", "timestamp"):
            array[:] = [0.1, 0.5, 0.5]
    group.create_array("index/k4/pose", shape=(3, 6), chunks=(1, 6), dtype="float64")
    group.create_array("progress", shape=(3,), chunks=(1,), dtype="bool", fill_value=False)[:] = (
        True
    )
    return path


def test_a_store_made_before_seals_is_refused_in_one_line(tmp_path):
    path = _old_store(tmp_path / "old.capture.zarr")
    with pytest.raises(InputError) as refused:
        CaptureStore.open(path)
    message = str(refused.value)
    assert f"schema version 1, expected {SCHEMA_VERSION}" in message and "\n" not in message


def test_the_report_serializes_for_json(store):
    (store / "frames/k4/c/0/0/0").unlink()
    document = json.loads(json.dumps(CaptureStore.open(store).check().as_dict()))
    assert document["verdict"] == "damaged" and document["missing_chunks"] == 1
    assert document["damaged"][0]["key"] == "frames/k4/c/0/0/0"
    assert document["damaged"][0]["units"] == [0]
