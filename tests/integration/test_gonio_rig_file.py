"""What the gonioreflectometer's calibration and processing take from the rig file
(ARCHITECTURE.md, "What calibration takes from the rig file").

:math:`F'_\\lambda` comes from the white standard's frames, jointly for camera, filter and lamp
(thesis Eq. 3.3-3.6), so neither the LCTF's passbands, the lamp's spectrum nor the camera's
quantum efficiency enter ``spectwin calibrate`` or ``spectwin process``. Two captures of the same
frames (same rig, same seed) whose stores record different rig models (another VariSpec, another
lamp, another camera) must therefore calibrate and process to the same numbers. The white
standard's reflectance, from its calibration certificate, is the one spectrum they read: scaling
it scales :math:`F'_\\lambda` by the same factor.
"""

from __future__ import annotations

import copy
import dataclasses
import json

import numpy as np
import pytest

from hwbridge.schema import Spectrum
from hwbridge.store import CaptureStore
from recon.btf.processing import prepare_gonio_run
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from twin.gonio.capture import GonioPairs, gonio_calibration_program, gonio_measurement_program
from twin.kinds.gonio import GONIO
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import GonioConfig, load_rig
from twin.sensor.band_weights import instrument_passbands

pytestmark = pytest.mark.render

CERTIFICATE_SCALE = 0.95
"""Factor on the white standard's certified reflectance in the store that records a changed one."""


def _other_rig_model(config: dict) -> dict:
    """The rig model with every model spectrum changed: the VS-20 for the VS-10 (20 nm passbands,
    not 10 nm), QTH lamps for HMI, another monochrome camera's quantum efficiency."""
    other = copy.deepcopy(config)
    other["camera"] |= {"filter": "VS-20", "definition": "basler_ccd12"}
    for lamp in other["lamps"]:
        lamp["spectrum"] = "qth"
    return other


def _recording(program, **rig):
    """``program`` capturing the same frames into a store whose ``rig`` attribute says ``rig``."""
    return dataclasses.replace(program, rig=program.rig.model_copy(update=rig))


def _calibrated(capture: CaptureStore, out) -> dict:
    """``spectwin calibrate``'s rig hook on ``capture``; the calibration file's document."""
    GONIO.calibrate(capture, out, {"white_fill": 0.7}, False)
    document = json.loads(out.read_text())
    del document["source"]  # the capture store's path
    return document


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    root = tmp_path_factory.mktemp("rig_file")
    calibration = gonio_calibration_program(pixels=32, spp=4, seed=5)
    other_model = _other_rig_model(calibration.rig.config)
    calibrations = {
        "as built": calibration.run(root / "cal.capture.zarr"),
        "other model": _recording(calibration, config=other_model).run(
            root / "cal_other.capture.zarr"
        ),
    }
    documents = {
        name: _calibrated(store, root / f"cal {name}.json") for name, store in calibrations.items()
    }
    exposures_s = np.asarray(documents["as built"]["planned_exposure_s"])
    pairs = GonioPairs(
        load_rig("gonio"),
        direction(np.array([30.0]), np.array([0.0])),
        direction(np.array([0.0]), np.array([0.0])),
    )
    run = gonio_measurement_program(exposures_s, pairs=pairs, pixels=128, spp=2, seed=6)
    white = run.rig.white_reflectance
    certificate = Spectrum(
        wavelengths_nm=white.wavelengths_nm,
        values=tuple(CERTIFICATE_SCALE * value for value in white.values),
    )
    runs = {
        "as built": run.run(root / "run.capture.zarr"),
        "other model": _recording(run, config=other_model).run(root / "run_other.capture.zarr"),
        "other certificate": _recording(run, white_reflectance=certificate).run(
            root / "run_white.capture.zarr"
        ),
    }
    return root, calibration.rig.config, other_model, documents, runs


def test_the_other_rig_model_has_other_passbands(stores):
    """The changed rig model is one that recon would notice if it read it: the instrument's band
    weights (filter x quantum efficiency x lamp) move by more than a third of their peak."""
    _, as_built, other, _, _ = stores
    models = (GonioConfig.model_validate(config) for config in (as_built, other))
    weights = [instrument_passbands(model).values for model in models]
    assert np.abs(weights[0] - weights[1]).max() > 0.33 * weights[0].max()


def test_calibration_takes_no_model_spectrum_from_the_rig_file(stores):
    """Response curve, F'_lambda, t_base and the exposure plan: the same to the last bit."""
    documents = stores[3]
    assert documents["as built"] == documents["other model"]


def test_processing_takes_no_model_spectrum_from_the_rig_file(stores):
    """The BTF (reflectance, corners, the run's F'_lambda) of the same frames is the same."""
    root, _, _, _, runs = stores
    btfs = {}
    for name in ("as built", "other model"):
        out = root / f"{name}.btf.zarr"
        GONIO.process(runs[name], root / "cal as built.json", out, {"texels": 16}, False)
        btfs[name] = BTFStore.open(out)
    built, other = btfs["as built"], btfs["other model"]
    assert built.complete and other.complete
    np.testing.assert_array_equal(built.read(), other.read())
    np.testing.assert_array_equal(built.corners_xy(), other.corners_xy())
    assert built.metadata.calibration == other.metadata.calibration


def test_the_white_standards_certificate_is_the_spectrum_processing_reads(stores):
    """F'_lambda of the run scales with the certified white reflectance (Eq. 3.3, 3.6)."""
    root, _, _, _, runs = stores
    calibration = GonioCalibration.load(root / "cal as built.json")
    factors = {
        name: prepare_gonio_run(runs[name], calibration).factors
        for name in ("as built", "other certificate")
    }
    np.testing.assert_allclose(
        factors["other certificate"], CERTIFICATE_SCALE * factors["as built"], rtol=1e-12
    )
