"""``spectwin export-frames`` and ``spectwin ingest`` on small stores and folders made here:
frames and records come back exactly, and bad folders, mappings and stores are refused in one
line with nothing written."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import tifffile
from typer.testing import CliRunner

from hwbridge.store import CaptureStore, FrameRecord
from twin.cli.app import app

runner = CliRunner()

# Two cameras of different frame sizes, interleaved; the spectral camera's lit frames carry a
# lamp monitor spectrum, a retried fault and a pose, as a real rig's can.
PLAN = [
    {"camera": "k4", "kind": "dark", "exposure_s": 1 / 15},
    {"camera": "rgb00", "kind": "alignment", "exposure_s": 0.004867964751410065, "view_id": 0},
    {"camera": "k4", "kind": "white", "exposure_s": 0.2, "band_nm": 550.0, "view_id": 3},
    {"camera": "rgb00", "kind": "sample", "exposure_s": 0.05, "view_id": 0, "light_id": 5},
    {
        "camera": "k4",
        "kind": "sample",
        "exposure_s": 2 / 3,
        "band_nm": 612.5,
        "view_id": 1,
        "light_id": 0,
    },
]
SHAPES = {"k4": (12, 16), "rgb00": (8, 8)}
RIG = {"rig": "bench", "program": "bench-run", "camera": "K4 behind a VariSpec"}


def _record(step: int, settings: dict) -> FrameRecord:
    lit = settings["kind"] != "dark" and settings["camera"] == "k4"
    return FrameRecord(
        kind=settings["kind"],
        exposure_s=settings["exposure_s"],
        timestamp=1.7e9 + step / 3,
        light_id=settings.get("light_id", -1),
        view_id=settings.get("view_id", -1),
        band_nm=settings.get("band_nm", float("nan")),
        status="ok after timeout" if step == 2 else "ok",
        pose=(0.1 * step, 0.2, 0.3, np.nan, 1e-7, -4.0) if lit else (np.nan,) * 6,
        lamp_monitor=np.array([0.1, 1 / 3, 2.5, 7.0], np.float32) * (step + 1) if lit else None,
    )


def _store(path: Path, done: int = len(PLAN)) -> CaptureStore:
    """A capture store of :data:`PLAN` with its first ``done`` steps written."""
    store = CaptureStore.create(
        path, rig=RIG, backend="real", seed=7, plan=PLAN, cameras=SHAPES, monitor_samples=4
    )
    rng = np.random.default_rng(5)
    for step, settings in enumerate(PLAN[:done]):
        frame = rng.integers(0, 4096, SHAPES[settings["camera"]], dtype=np.uint16)
        store.write_frame(step, frame, _record(step, settings))
        store.mark_done(step)
    return store


@pytest.fixture(scope="module")
def exported(tmp_path_factory) -> tuple[CaptureStore, Path]:
    """A complete store and the folder export-frames wrote from it."""
    root = tmp_path_factory.mktemp("frames")
    store = _store(root / "bench.capture.zarr")
    result = runner.invoke(
        app, ["export-frames", str(store.path), "--out", str(root / "bench"), "--json"]
    )
    assert result.exit_code == 0, result.output
    return store, root / "bench"


def test_export_writes_named_tiffs_sidecars_and_the_session(exported):
    store, folder = exported
    names = sorted(path.name for path in (folder / "frames" / "k4").iterdir())
    assert names == [
        "s000000_dark_e0.06666666666666667s.json",
        "s000000_dark_e0.06666666666666667s.tif",
        "s000002_white_e0.2s_b550.0nm_v3.json",
        "s000002_white_e0.2s_b550.0nm_v3.tif",
        "s000004_sample_e0.6666666666666666s_b612.5nm_v1_l0.json",
        "s000004_sample_e0.6666666666666666s_b612.5nm_v1_l0.tif",
    ]
    frame = tifffile.imread(folder / "frames" / "k4" / names[3])
    assert frame.dtype == np.uint16 and frame.shape == (12, 16)
    np.testing.assert_array_equal(frame, store.frames("k4")[1])
    session = json.loads((folder / "session.json").read_text())
    assert session["rig"] == RIG and session["seed"] == 7 and session["backend"] == "real"
    assert session["plan"] == PLAN and session["cameras"] == {"k4": [12, 16], "rgb00": [8, 8]}
    sidecar = json.loads((folder / "frames" / "k4" / names[2]).read_text())
    assert sidecar["status"] == "ok after timeout" and sidecar["step"] == 2
    assert sidecar["lamp_monitor"][1] == float(np.float32(1 / 3) * np.float32(3))


def test_export_then_ingest_gives_back_every_frame_and_record(exported, tmp_path):
    store, folder = exported
    out = tmp_path / "again.capture.zarr"
    result = runner.invoke(
        app, ["ingest", str(folder), "--mapping", "spectwin", "--out", str(out), "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["frames"] == 5 and summary["cameras"] == {"k4": 3, "rgb00": 2}
    assert summary["rig"] == "bench" and summary["complete"] is True
    again = CaptureStore.open(out)
    assert again.attrs["rig"] == RIG and again.metadata.seed == 7
    assert again.metadata.backend == "replay"
    plan = again.attrs["plan"]
    assert [{k: v for k, v in step.items() if k != "file"} for step in plan] == PLAN
    assert plan[4]["file"] == "frames/k4/s000004_sample_e0.6666666666666666s_b612.5nm_v1_l0.tif"
    for camera in SHAPES:
        np.testing.assert_array_equal(again.frames(camera)[:], store.frames(camera)[:])
        original, ingested = store.index(camera), again.index(camera)
        assert sorted(original) == sorted(ingested)
        for name, values in original.items():
            if name != "seal":  # a frame's seal binds it to its own store
                np.testing.assert_array_equal(ingested[name], values, err_msg=name)


def _export_copy(exported, tmp_path: Path) -> Path:
    folder = tmp_path / "frames"
    shutil.copytree(exported[1], folder)
    return folder


def _mapping(tmp_path: Path, text: str) -> str:
    path = tmp_path / "mapping.yaml"
    path.write_text(text)
    return str(path)


def _tiffs(tmp_path: Path, frames: dict[str, np.ndarray]) -> Path:
    """A folder of TIFFs by name."""
    folder = tmp_path / "frames"
    folder.mkdir()
    for name, frame in frames.items():
        tifffile.imwrite(folder / name, frame)
    return folder


FLAT = "camera: cam\nfiles:\n  - pattern: 'f_(?P<exposure_ms>\\d+)ms\\.tif'\n    kind: white\n"
PIXELS = np.arange(12, dtype=np.uint16).reshape(3, 4)


def _unknown_key(exported, tmp_path):
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, FLAT + "camra: x\n")


def _bad_regex(exported, tmp_path):
    mapping = "camera: c\nfiles:\n  - pattern: 'f_(?P<exposure_ms>\\d+ms\\.tif'\n    kind: dark\n"
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, mapping)


def _unknown_group(exported, tmp_path):
    mapping = "camera: c\nfiles:\n  - pattern: 'f_(?P<exposure>\\d+)ms\\.tif'\n    kind: dark\n"
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, mapping)


def _not_yaml(exported, tmp_path):
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, "files: [a\n  b: :")


def _matches_nothing(exported, tmp_path):
    mapping = FLAT + "  - pattern: 'd_(?P<exposure_ms>\\d+)ms\\.tif'\n    kind: dark\n"
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, mapping)


def _sizes_differ(exported, tmp_path):
    frames = {"f_10ms.tif": PIXELS, "f_20ms.tif": PIXELS[:2]}
    return _tiffs(tmp_path, frames), _mapping(tmp_path, FLAT)


def _bit_depths_differ(exported, tmp_path):
    frames = {"f_10ms.tif": PIXELS, "f_20ms.tif": PIXELS.astype(np.uint8)}
    return _tiffs(tmp_path, frames), _mapping(tmp_path, FLAT)


def _float_frame(exported, tmp_path):
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS.astype(np.float32)}), _mapping(tmp_path, FLAT)


def _unreadable_tiff(exported, tmp_path):
    folder = _tiffs(tmp_path, {"f_10ms.tif": PIXELS})
    cut = (folder / "f_10ms.tif").read_bytes()[:100]  # a copy cut short
    (folder / "f_20ms.tif").write_bytes(cut)
    return folder, _mapping(tmp_path, FLAT)


def _no_exposure(exported, tmp_path):
    mapping = "camera: c\nfiles:\n  - pattern: 'f_\\d+ms\\.tif'\n    kind: white\n"
    return _tiffs(tmp_path, {"f_10ms.tif": PIXELS}), _mapping(tmp_path, mapping)


def _bad_kind(exported, tmp_path):
    mapping = "camera: c\nfiles:\n  - pattern: '(?P<kind>\\w+)_(?P<exposure_ms>\\d+)\\.tif'\n"
    return _tiffs(tmp_path, {"selfie_10.tif": PIXELS}), _mapping(tmp_path, mapping)


WHITE = "frames/k4/s000002_white_e0.2s_b550.0nm_v3"  # a frame of the export, without suffix


def _removed(file):
    """A copy of the export without ``file``."""

    def make(exported, tmp_path):
        folder = _export_copy(exported, tmp_path)
        (folder / file).unlink()
        return folder, "spectwin"

    return make


def _renamed(stem):
    """A copy of the export with the frame :data:`WHITE` and its sidecar renamed ``stem``."""

    def make(exported, tmp_path):
        folder = _export_copy(exported, tmp_path)
        for suffix in (".tif", ".json"):
            (folder / f"{WHITE}{suffix}").rename(folder / f"frames/k4/{stem}{suffix}")
        return folder, "spectwin"

    return make


def _sidecar_unknown_field(exported, tmp_path):
    folder = _export_copy(exported, tmp_path)
    sidecar = folder / f"{WHITE}.json"
    sidecar.write_text(json.dumps(json.loads(sidecar.read_text()) | {"gain": 2}))
    return folder, "spectwin"


def _unknown_mapping(exported, tmp_path):
    return _export_copy(exported, tmp_path), "spectwin-gonio"


def _rig_and_session(exported, tmp_path):
    text = (Path(__file__).parents[3] / "hwbridge/mappings/spectwin.yaml").read_text()
    return _export_copy(exported, tmp_path), _mapping(tmp_path, text + "rig: {name: x}\n")


BAD_INGESTS = {
    "unknown mapping key": (_unknown_key, "camra: Extra inputs are not permitted"),
    "bad regular expression": (_bad_regex, "not a regular expression (missing )"),
    "unknown named group": (_unknown_group, "named groups ['exposure']: expected groups among"),
    "mapping not YAML": (_not_yaml, "not a YAML file"),
    "pattern matches nothing": (
        _matches_nothing,
        "files.1 pattern d_(?P<exposure_ms>\\d+)ms\\.tif matches no file",
    ),
    "frame sizes differ": (_sizes_differ, "uint16 (2, 4), but f_10ms.tif is uint16 (3, 4)"),
    "bit depths differ": (_bit_depths_differ, "uint8 (3, 4), but f_10ms.tif is uint16 (3, 4)"),
    "float frame": (_float_frame, "a float32 frame of shape (3, 4): expected one monochrome"),
    "unreadable TIFF": (
        _unreadable_tiff,
        "f_20ms.tif: not a readable TIFF (corrupted IFD structure)",
    ),
    "no exposure field": (_no_exposure, "f_10ms.tif: no exposure: expected an exposure_ms"),
    "unknown kind": (_bad_kind, "selfie_10.tif: kind 'selfie': expected one of"),
    "export not finished": (_removed("session.json"), "session.json: no session file"),
    "a step without its frame": (
        _removed("frames/rgb00/s000003_sample_e0.05s_v0_l5.tif"),
        "1 of 5 steps have no frame (first step 3)",
    ),
    "band missing from a name": (
        _renamed("s000002_white_e0.2s_v3"),
        "no band_nm in its name; step 2 has 550.0",
    ),
    "name disagrees with the plan": (
        _renamed("s000002_white_e0.4s_b550.0nm_v3"),
        "exposure_s 0.4 in its name, but step 2",
    ),
    "sidecar missing": (
        _removed(f"{WHITE}.json"),
        "no sidecar s000002_white_e0.2s_b550.0nm_v3.json",
    ),
    "sidecar unknown field": (_sidecar_unknown_field, "gain: Extra inputs are not permitted"),
    "no such mapping": (_unknown_mapping, "expected a path or one of ['llanos2019', 'spectwin']"),
    "rig and session": (_rig_and_session, "rig and session: expected one"),
}


def _refused(arguments: list[str], message: str) -> None:
    """``spectwin ARGUMENTS`` exits 2 with one line ``error: ...`` holding ``message``."""
    result = runner.invoke(app, arguments)
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1, result.stderr
    assert message in result.stderr


@pytest.mark.parametrize("case", BAD_INGESTS)
def test_bad_ingests_are_refused_in_one_line_and_write_nothing(exported, tmp_path, case):
    make, message = BAD_INGESTS[case]
    source, mapping = make(exported, tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    store = out / "run.capture.zarr"
    _refused(["ingest", str(source), "--mapping", mapping, "--out", str(store)], message)
    assert list(out.iterdir()) == []


def test_an_existing_store_is_refused_before_the_frames_are_read(exported, tmp_path):
    store = tmp_path / "run.capture.zarr"
    store.mkdir()
    (store / "keep").write_text("mine")
    folder = _export_copy(exported, tmp_path)
    arguments = ["ingest", str(folder), "--mapping", "spectwin", "--out", str(store)]
    _refused(arguments, "run.capture.zarr exists: expected a new store")
    assert [path.name for path in store.iterdir()] == ["keep"]


def _missing_store(exported, tmp_path):
    return tmp_path / "nothing.capture.zarr", tmp_path / "out"


def _incomplete_store(exported, tmp_path):
    return _store(tmp_path / "half.capture.zarr", done=3).path, tmp_path / "out"


def _full_folder(exported, tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "notes.txt").write_text("mine")
    return exported[0].path, tmp_path / "out"


def _file_as_folder(exported, tmp_path):
    (tmp_path / "out").write_text("mine")
    return exported[0].path, tmp_path / "out"


BAD_EXPORTS = {
    "no store": (_missing_store, "nothing.capture.zarr does not exist: expected a capture store"),
    "incomplete store": (_incomplete_store, "incomplete (2 of 5 steps pending, first step 3)"),
    "folder not empty": (_full_folder, "out exists and is not an empty folder"),
    "out is a file": (_file_as_folder, "out exists and is not an empty folder"),
}


@pytest.mark.parametrize("case", BAD_EXPORTS)
def test_bad_exports_are_refused_in_one_line_and_write_nothing(exported, tmp_path, case):
    make, message = BAD_EXPORTS[case]
    store, out = make(exported, tmp_path)
    before = sorted(path.name for path in out.iterdir()) if out.is_dir() else None
    _refused(["export-frames", str(store), "--out", str(out)], message)
    after = sorted(path.name for path in out.iterdir()) if out.is_dir() else None
    assert after == before
