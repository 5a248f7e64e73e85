"""Replay of the real llanos2019 capture into a capture store."""

import numpy as np
import pytest
import tifffile

from hwbridge.errors import InputError
from hwbridge.replay import ingest, load_mapping
from hwbridge.store import CaptureStore
from recon.measured_data import data_path

SOURCE = data_path("real/llanos2019")


def test_llanos2019_becomes_a_complete_capture_store(tmp_path):
    store = ingest(SOURCE, "llanos2019", tmp_path / "llanos.capture.zarr")
    assert store.complete and store.attrs["backend"] == "replay"
    frames, index = store.frames("flea3"), store.index("flea3")
    assert frames.shape == (14 + 49, 342, 408) and frames.dtype == np.uint16
    kinds = list(index["kind"])
    assert kinds.count("dark") == 14 and kinds.count("chart") == 49
    assert sorted(set(np.round(index["exposure_s"], 3))) == [
        0.025,
        0.05,
        0.1,
        0.25,
        0.5,
        2.0,
        3.916,
    ]
    chart = index["kind"] == "chart"
    assert sorted(set(index["band_nm"][chart])) == [400, 450, 500, 550, 600, 650, 700]
    # Frames are the files' pixels, exactly.
    step = store.attrs["plan"].index(next(s for s in store.attrs["plan"] if s["kind"] == "chart"))
    file = store.attrs["plan"][step]["file"]
    slot = step  # one camera: plan order is slot order
    np.testing.assert_array_equal(frames[slot], tifffile.imread(SOURCE / file))
    # Longer exposures collect more light (a sanity check on the exposure parsing).
    at_550 = chart & (index["band_nm"] == 550)
    means = {
        float(t): frames[i].mean()
        for i, t in zip(np.flatnonzero(at_550), index["exposure_s"][at_550], strict=True)
    }
    assert means[0.5] > means[0.025]
    reopened = CaptureStore.open(tmp_path / "llanos.capture.zarr")
    assert reopened.pending_steps() == []


def test_bad_mappings_and_sources_are_refused(tmp_path):
    with pytest.raises(InputError, match="llanos2019"):
        load_mapping("nope")
    bad = tmp_path / "bad.yaml"
    bad.write_text("camera: c\nfiles:\n  - pattern: 'x'\n    kind: selfie\n")
    with pytest.raises(InputError, match="files.0.kind: Input should be .dark."):
        load_mapping(bad)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="files.0 pattern .* matches no file in"):
        ingest(empty, "llanos2019", tmp_path / "x.zarr")
