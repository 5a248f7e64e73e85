"""Stores that cannot lie (issue 42, items 1 and 2), for both kinds of store.

Every unit's chunk (a capture's frame, a BTF's pair) is sealed to its array, its place and the
store, so a swapped, moved, foreign or reshaped chunk is found by name, refused by readers and
done again on resuming (a simulated capture takes the frame again; processing finds the pair
pending). The settings that define a store (a capture's plan, rig, backend and seed; a BTF's
material, calibration, source, rig, directions and bands) and its arrays' shapes are sealed at
creation, so an edit is refused in one line naming it."""

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from hwbridge.errors import DamagedDataError
from hwbridge.store import CaptureStore, FrameRecord
from recon.btf.store import BTFStore, write_btf
from recon.spectra import DEFAULT_GRID, WavelengthGrid

PLAN = [
    {"camera": "k4", "kind": "sample", "exposure_s": 0.5, "band_nm": 400.0 + 10 * i}
    for i in range(5)
]
DIRECTIONS = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [0.8, 0.0, 0.6]])


def _capture(path: Path, seed: int = 5, side: int = 16) -> Path:
    """A complete simulated capture store of 5 frames (``side`` x 12 px)."""
    store = CaptureStore.create(
        path,
        rig={"rig": "gonioreflectometer", "program": "test"},
        backend="sim",
        seed=seed,
        plan=PLAN,
        cameras={"k4": (side, 12)},
    )
    for step in range(len(PLAN)):
        frame = np.random.default_rng([seed, step]).integers(100, 4000, (side, 12))
        store.write_frame(step, frame.astype(np.uint16), FrameRecord("sample", 0.5, 1.0))
        store.mark_done(step)
    return path


def _btf(
    path: Path,
    seed: int = 5,
    side: int = 3,
    grid: WavelengthGrid = DEFAULT_GRID,
    light_dirs: np.ndarray = DIRECTIONS,
) -> Path:
    """A complete BTF store of 4 pairs of ``side`` x ``side`` texels."""
    values = np.random.default_rng(seed).uniform(0.05, 0.9, (4, side, side, grid.size))
    write_btf(
        path,
        values.astype(np.float32),
        grid,
        light_dirs=light_dirs,
        view_dirs=light_dirs[::-1],
        material="colorchecker16",
        calibration={"white": 0.99},
        source_capture="run.capture.zarr",
    )
    return path


def _capture_resumed(path: Path) -> list[int]:
    store = CaptureStore.open(path)
    store.prepare_resume()
    return store.pending_steps()


def _btf_resumed(path: Path) -> list[int]:
    store = BTFStore.open(path, writable=True)
    store.prepare_resume()
    return store.pending_pairs()


@dataclass(frozen=True)
class Kind:
    """A kind of store as these tests use it: ``make(path, seed=, side=)`` makes one (``side``:
    chunks of another shape), ``key`` and ``other`` are the chunks of its units 3 and 1,
    ``read(path)`` reads unit 3, ``resumed(path)`` prepares a resume and lists the pending
    units, ``name`` is unit 3 in messages."""

    make: Callable[..., Path]
    key: str
    other: str
    read: Callable[[Path], object]
    resumed: Callable[[Path], list[int]]
    name: str


KINDS = {
    "capture": Kind(
        _capture,
        "frames/k4/c/3/0/0",
        "frames/k4/c/1/0/0",
        lambda path: CaptureStore.open(path).read_frames("k4", [3]),
        _capture_resumed,
        "step 3 (frame 3)",
    ),
    "BTF": Kind(
        _btf,
        "reflectance/c/3/0/0/0",
        "reflectance/c/1/0/0/0",
        lambda path: BTFStore.open(path).read_pair(3),
        _btf_resumed,
        "pair 3",
    ),
}


def _open(path: Path) -> CaptureStore | BTFStore:
    return CaptureStore.open(path) if path.name.endswith(".capture.zarr") else BTFStore.open(path)


@pytest.fixture(scope="module")
def donors(tmp_path_factory):
    """Per kind of store: one like the tested one but of other data, and one of smaller
    chunks."""
    root = tmp_path_factory.mktemp("donors")
    return {
        name: {
            "foreign": kind.make(root / f"foreign.{name.lower()}.zarr", seed=6),
            "reshaped": kind.make(root / f"reshaped.{name.lower()}.zarr", side=2),
        }
        for name, kind in KINDS.items()
    }


@pytest.mark.parametrize("kind", KINDS)
def test_a_misplaced_chunk_is_named_refused_and_done_again(kind, tmp_path, donors, misplace):
    store = KINDS[kind]
    path = store.make(tmp_path / f"run.{kind.lower()}.zarr")
    misplace(path, store.key, store.other, donors[kind])
    report = _open(path).check()
    damaged = {problem.key for problem in report.problems}
    assert store.key in damaged and not report.healthy
    assert damaged <= {store.key, store.other}  # a swap damages both places, nothing else is
    with pytest.raises(
        DamagedDataError, match=re.escape(f"{store.name}: {store.key} is corrupt (")
    ):
        store.read(path)
    assert 3 in store.resumed(path)


def _shape(axis: int, size: int) -> Callable[[dict], None]:
    return lambda document: document["shape"].__setitem__(axis, size)


def _attribute(**values: object) -> Callable[[dict], None]:
    return lambda document: document["attributes"].update(values)


EDITS = {
    "capture seed": ("capture", "zarr.json", _attribute(seed=0), "seed"),
    "capture plan": (
        "capture",
        "zarr.json",
        lambda document: document["attributes"]["plan"][2].update(exposure_s=1.0),
        "plan",
    ),
    "capture rig": ("capture", "zarr.json", _attribute(rig={"rig": "x", "program": "y"}), "rig"),
    "capture backend": ("capture", "zarr.json", _attribute(backend="real"), "backend"),
    "capture frames": ("capture", "frames/k4/zarr.json", _shape(0, 4), "frames/k4"),
    "capture frame height": ("capture", "frames/k4/zarr.json", _shape(1, 8), "frames/k4"),
    "capture index": ("capture", "index/k4/kind/zarr.json", _shape(0, 4), "index/k4/kind"),
    "capture progress": ("capture", "progress/zarr.json", _shape(0, 4), "progress"),
    "BTF material": ("BTF", "zarr.json", _attribute(material="wallpaper"), "material"),
    "BTF calibration": ("BTF", "zarr.json", _attribute(calibration={"white": 1}), "calibration"),
    "BTF source": ("BTF", "zarr.json", _attribute(source_capture="b"), "source_capture"),
    "BTF rig": ("BTF", "zarr.json", _attribute(rig="dome"), "rig"),
    "BTF texels": ("BTF", "reflectance/zarr.json", _shape(1, 2), "reflectance"),
    "BTF pairs": ("BTF", "reflectance/zarr.json", _shape(0, 3), "reflectance"),
    "BTF flags": ("BTF", "written/zarr.json", _shape(0, 3), "written"),
}


@pytest.mark.parametrize(("kind", "node", "edit", "named"), EDITS.values(), ids=EDITS)
def test_an_edited_setting_or_shape_is_refused_in_one_line(
    kind, node, edit, named, tmp_path, edit_metadata
):
    path = KINDS[kind].make(tmp_path / f"run.{kind.lower()}.zarr")
    edit_metadata(path / node, edit)
    with pytest.raises(DamagedDataError) as refused:
        _open(path)
    message = str(refused.value)
    assert f"{named} differs from what the store was created with" in message
    assert str(path) in message and "\n" not in message


@pytest.mark.parametrize("array", ["light_dirs/c/0/0", "view_dirs/c/0/0", "wavelengths/c/0"])
def test_directions_or_wavelengths_from_another_btf_are_refused(tmp_path, array):
    path = _btf(tmp_path / "run.btf.zarr")
    grid = WavelengthGrid(np.array([450.0, 550.0, 650.0]))
    other = _btf(tmp_path / "other.btf.zarr", grid=grid, light_dirs=DIRECTIONS[[1, 0, 3, 2]])
    (path / array).write_bytes((other / array).read_bytes())
    with pytest.raises(DamagedDataError, match=array.split("/")[0]) as refused:
        BTFStore.open(path)
    assert "\n" not in str(refused.value)
