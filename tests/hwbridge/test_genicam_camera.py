"""The GenICam camera driver against the simulated GenTL producer of the genicam package."""

import numpy as np
import pytest

from hwbridge.drivers import genicam_camera
from hwbridge.errors import DeviceError, InputError
from hwbridge.protocols import Camera

# The driver imports harvesters only when it stages a camera: skip here without the extra.
pytest.importorskip("harvesters")


@pytest.fixture
def camera():
    device = genicam_camera.GenICamCamera(genicam_camera.simulated_producer(), serial_number="1")
    device.stage()
    yield device
    device.unstage()


def test_snaps_frames_of_the_advertised_size(camera):
    assert isinstance(camera, Camera)
    frame, metadata = camera.snap()
    assert frame.dtype == np.uint16 and frame.shape == camera.frame_shape
    assert metadata["exposure_s"] is None and metadata["pixel_format"]
    second, _ = camera.snap()
    assert second.shape == frame.shape
    assert "GenICam" in camera.describe()["camera_image"]["source"]


def test_wrong_serials_producers_and_exposures_are_reported(tmp_path):
    with pytest.raises(DeviceError, match="no camera with serial"):
        genicam_camera.GenICamCamera(
            genicam_camera.simulated_producer(), serial_number="999"
        ).stage()
    with pytest.raises(InputError, match="does not exist"):
        genicam_camera.GenICamCamera(tmp_path / "none.cti").stage()
    with pytest.raises(DeviceError, match="not staged"):
        genicam_camera.GenICamCamera(genicam_camera.simulated_producer()).snap()


def test_a_camera_without_an_exposure_time_is_refused_an_exposure(camera):
    """The simulated producer's camera has no ExposureTime feature: a plan's exposure cannot
    be set, and the driver says so rather than store frames under an exposure they were not
    taken at."""
    assert camera.identity() == {
        "model": "Machine Vision Games Ltd. Viky",
        "serial": "1",
        "firmware": "1.0",
    }
    with pytest.raises(DeviceError, match="has no ExposureTime feature"):
        camera.set_exposure(0.01)


def test_a_failed_stage_releases_the_producer_for_the_next_camera():
    with pytest.raises(DeviceError, match="no camera with serial"):
        genicam_camera.GenICamCamera(
            genicam_camera.simulated_producer(), serial_number="999"
        ).stage()
    # A harvester left behind by the failed stage would hide the producer's cameras.
    camera = genicam_camera.GenICamCamera(genicam_camera.simulated_producer())
    camera.stage()
    try:
        assert camera.snap()[0].dtype == np.uint16
    finally:
        camera.unstage()
