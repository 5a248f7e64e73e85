"""Calibration code reads a replayed real capture exactly like a simulated one."""

import numpy as np
import pytest
import tifffile

from hwbridge.replay import ingest
from recon.calibration.capture_io import select_frames
from recon.errors import InputError
from recon.measured_data import data_path
from twin.gonio.sim_session import run_demo_session
from twin.sensor.model import Sensor


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stores")
    replay = ingest(data_path("real/llanos2019"), "llanos2019", folder / "llanos.capture.zarr")
    simulated = run_demo_session(folder / "sim.capture.zarr", 4)
    return {"replay": (replay, "flea3", 0.1), "sim": (simulated, "k4", 0.1)}


@pytest.mark.parametrize("backend", ["replay", "sim"])
def test_dark_frames_read_the_same_way_from_either_backend(stores, backend):
    store, camera, exposure = stores[backend]
    darks = select_frames(store, camera, kind="dark", exposure_s=exposure)
    assert darks.backend == backend
    assert darks.frames.ndim == 3 and darks.frames.dtype == np.float64
    assert np.all(np.isclose(darks.exposure_s, exposure)) and len(darks.frames) >= 2
    # A mean dark frame, as the calibration averages them (thesis 3.3).
    mean_dark = darks.frames.mean(axis=0)
    assert mean_dark.shape == darks.frames.shape[1:] and np.isfinite(mean_dark).all()
    if backend == "replay":
        # The frames are the two 100 ms dark files, read with tifffile; the exposure comes from
        # "_100ms_" in their names.
        files = sorted((data_path("real/llanos2019") / "captured_images" / "dark_frames").glob("*"))
        at_100_ms = [file for file in files if "_100ms_" in file.name]
        assert len(at_100_ms) == 2 and np.all(darks.exposure_s == 0.1)
        for frame, file in zip(darks.frames, at_100_ms, strict=True):
            np.testing.assert_array_equal(frame, tifffile.imread(file).astype(np.float64))
    else:
        # The simulated camera's dark level: its ADC offset (100 DN) plus 0.0016 DN of dark
        # current, with read noise 3 DN per pixel: the mean of the frames' pixels within five
        # of its standard errors (3 DN / sqrt(pixels); 0.054 DN for three 32 x 32 frames).
        config = Sensor("coolsnap_k4").config
        assert len(darks.frames) == 3
        standard_error = config.read_noise_dn / np.sqrt(darks.frames.size)
        assert darks.frames.mean() == pytest.approx(config.adc_offset_dn, abs=5 * standard_error)
        assert darks.frames.std() == pytest.approx(config.read_noise_dn, rel=0.03)


def test_band_selection_and_clear_errors(stores):
    store, camera, _ = stores["replay"]
    at_550 = select_frames(store, camera, kind="chart", band_nm=550)
    assert len(at_550.frames) == 7 and np.all(at_550.band_nm == 550)
    with pytest.raises(InputError, match="no 'white' frames"):
        select_frames(store, camera, kind="white")
