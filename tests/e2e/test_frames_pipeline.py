"""Twin captures of both rigs written out by ``spectwin export-frames``, read back by
``spectwin ingest --mapping spectwin`` and calibrated and processed: the same calibrations and
BTFs as from the original stores, as a real rig's folder of frames would give.

Small captures: the gonioreflectometer's calibration session (64 px, 4 spp) and a run of one
direction pair at 96 px and 2 spp, processed at 16 texels; the dome's calibration and a run of
the Lego bricks at one stage position, 3 LEDs, 2 RGB cameras, 8 texels and 4 spp. (The round
trip's time goes to writing and reading the stores' frames and calibrating, not to rendering.)
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.gonio.capture import GonioPairs, run_gonio_calibration, run_gonio_measurement
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render

DOME = DomeCaptureSize(stage_positions=1, leds=3, rgb_cameras=2, texels=8, spp=4)
CALIBRATION_FILE = {"gonio": "cal.json", "dome": "cal.npz"}


@pytest.fixture(scope="module")
def captures(tmp_path_factory, invoke_json):
    """The original capture stores of both rigs, calibration and run, and their processing."""
    root = tmp_path_factory.mktemp("captures")
    # 4 samples per pixel (the fewest rendered): a quarter of the default's render time
    run_gonio_calibration(root / "gonio_cal.capture.zarr", spp=4, seed=1)
    invoke_json(
        "calibrate", root / "gonio_cal.capture.zarr", "--out", root / "gonio.json", "--json"
    )
    pairs = GonioPairs(
        load_rig("gonio"),
        direction(np.array([30.0]), np.array([0.0])),
        direction(np.array([0.0]), np.array([0.0])),
    )
    exposures_s = GonioCalibration.load(root / "gonio.json").planned_exposure_s
    run_gonio_measurement(
        root / "gonio_run.capture.zarr", exposures_s, pairs=pairs, pixels=96, spp=2, seed=3
    )
    dome_calibration_program(size=DOME, dark_frames=2, seed=4).run(root / "dome_cal.capture.zarr")
    dome_run_program("lego", size=DOME, seed=4).run(root / "dome_run.capture.zarr")
    return root


def _process(invoke_json, calibration_store, run_store, folder, rig):
    """``spectwin calibrate`` and ``spectwin process``: the calibration file and the BTF."""
    folder.mkdir()
    calibration = folder / CALIBRATION_FILE[rig]
    invoke_json("calibrate", calibration_store, "--out", calibration, "--json")
    btf = folder / "btf.zarr"
    options = ["--texels", 16] if rig == "gonio" else []
    invoke_json(
        "process", run_store, "--calibration", calibration, "--out", btf, *options, "--json"
    )
    return calibration, BTFStore.open(btf)


def _through_frames(invoke_json, store, root):
    """``store`` exported to a folder of frames and ingested again."""
    folder, again = root / f"{store.name}.frames", root / f"again_{store.name}"
    exported = invoke_json("export-frames", store, "--out", folder, "--json")
    ingested = invoke_json("ingest", folder, "--mapping", "spectwin", "--out", again, "--json")
    assert ingested["frames"] == exported["frames"] and ingested["complete"]
    return again


def _without_source(text: str) -> dict:
    """A calibration's JSON but the path of the store it was made from."""
    summary = json.loads(text)
    summary.pop("source")
    return summary


def _same_calibration(original, again):
    """The calibration files are equal but for the path of their capture store."""
    if original.suffix == ".json":
        assert _without_source(again.read_text()) == _without_source(original.read_text())
        return
    with np.load(original) as first, np.load(again) as second:
        assert sorted(first.files) == sorted(second.files)
        assert _without_source(str(second["summary"])) == _without_source(str(first["summary"]))
        for name in set(first.files) - {"summary"}:
            np.testing.assert_array_equal(second[name], first[name], err_msg=name)


@pytest.mark.parametrize("rig", ["gonio", "dome"])
def test_exported_and_ingested_captures_process_to_the_same_btf(captures, invoke_json, rig):
    root = captures
    stores = [root / f"{rig}_{program}.capture.zarr" for program in ("cal", "run")]
    original = _process(invoke_json, *stores, root / f"{rig}_original", rig)
    ingested = [_through_frames(invoke_json, store, root) for store in stores]
    for store, again in zip(stores, ingested, strict=True):
        first, second = CaptureStore.open(store), CaptureStore.open(again)
        assert second.attrs["rig"] == first.attrs["rig"]
        assert second.metadata.seed == first.metadata.seed
        plan = [{k: v for k, v in step.items() if k != "file"} for step in second.attrs["plan"]]
        assert plan == first.attrs["plan"]
        for camera in dict.fromkeys(step["camera"] for step in plan):
            np.testing.assert_array_equal(second.frames(camera)[:], first.frames(camera)[:])
            index = second.index(camera)
            for name, values in first.index(camera).items():
                if name != "seal":  # a frame's seal binds it to its own store
                    np.testing.assert_array_equal(index[name], values, err_msg=name)
    again = _process(invoke_json, *ingested, root / f"{rig}_again", rig)
    _same_calibration(original[0], again[0])
    first, second = original[1], again[1]
    assert first.shape == second.shape and second.complete
    np.testing.assert_array_equal(second.read(), first.read())
    np.testing.assert_array_equal(second.corners_xy(), first.corners_xy())
    differing = {
        name
        for name in first.attrs.keys() | second.attrs.keys()
        if first.attrs.get(name) != second.attrs.get(name)
    }
    # Paths, and what names its store and inputs: the identity (random, made at creation), the
    # seals made with it, and the hashes of the capture (its identity) and the calibration file.
    own = {"store_id", "sealed", "inputs"}
    assert differing <= {"source_capture", "calibration"} | own, differing
