"""A kind of rig defined only here goes through capture, calibrate, process and evaluate by the
registry alone: a flat-field spectral camera (a CoolSNAP K4 window behind a simulated tunable
filter) looking at one ColorChecker patch, calibrated on a white standard.

The capture runs the real session code into a real capture store; ``spectwin calibrate``,
``process`` and ``evaluate`` find the rig by the name the stores record. The recovered
reflectance is checked against the patch's measured spectrum (colour-science's ColorChecker N
Ohta) within the photon noise the sensor model gives.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import colour
import numpy as np
import pytest
from typer.testing import CliRunner

from hwbridge.plans import plan_start_times_s
from hwbridge.schema import RigAttrs
from hwbridge.session import SessionDevices
from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.spectra import WavelengthGrid
from twin.cli.app import app
from twin.devices.programs import ProgramCapture
from twin.devices.sim_devices import SimCamera, SimTunableFilter, VirtualRig
from twin.kinds.registry import (
    Outcome,
    ProgramKind,
    ProgramSettings,
    RigKind,
    capture_program,
    register,
    rig_kind,
    unregister,
)
from twin.rigs.yaml_config import StrictModel
from twin.sensor.model import Sensor
from twin.studies.sweep_file import SweepKind

NAME = "flat-field"
BANDS_NM = np.arange(450.0, 701.0, 50.0)
EXPOSURE_S = 0.5
ELECTRONS_PER_S = 20_000.0  # the white standard's photo-electrons per pixel and second
PIXELS = 16
WHITE = 0.99
PATCH = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]["moderate red"]
runner = CliRunner()


def _truth() -> np.ndarray:
    return np.array([PATCH[band] for band in BANDS_NM])


@dataclass(frozen=True)
class _Signal:
    reflectance: tuple[float, ...]

    def __call__(self, rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
        band = int(np.argmin(np.abs(BANDS_NM - rig.band_nm)))
        electrons = ELECTRONS_PER_S * self.reflectance[band] * exposure_s
        return np.full((PIXELS, PIXELS), electrons)


@dataclass(frozen=True)
class _Devices:
    reflectance: tuple[float, ...]
    plan: tuple[dict, ...]
    backend: ClassVar[str] = "sim"

    def __call__(self, seed: int = 0, steps: Sequence[int] | None = None) -> SessionDevices:
        rig = VirtualRig(seed=seed, steps=None if steps is None else tuple(steps))
        sensor = Sensor("coolsnap_k4", roi=(PIXELS, PIXELS))
        starts = plan_start_times_s(list(self.plan))
        camera = SimCamera(rig, sensor, _Signal(self.reflectance), starts, name="camera")
        return SessionDevices(cameras={"camera": camera}, tunable_filter=SimTunableFilter(rig))


class _Program(ProgramCapture):
    def __init__(self, name: str, reflectance: np.ndarray, seed: int):
        self.name, self.seed = name, seed
        self.plan = [
            {"camera": "camera", "kind": kind, "band_nm": float(band), "exposure_s": EXPOSURE_S}
            for band in BANDS_NM
            for kind in ("dark", "sample")
        ]
        self.devices = _Devices(tuple(float(value) for value in reflectance), tuple(self.plan))
        self.rig = {"rig": NAME, "program": name}

    def dry_run(self) -> dict[str, object]:
        return {"program": self.name, "steps": len(self.plan)}


def _mean_signal(capture: CaptureStore) -> np.ndarray:
    """Dark-subtracted mean DN per band."""
    index = capture.index("camera", ["kind", "band_nm"])
    frames = capture.read_frames("camera", list(range(len(index["kind"])))).astype(np.float64)
    means = []
    for band in BANDS_NM:
        at = index["band_nm"] == band
        dark = frames[at & (index["kind"] == "dark")].mean()
        means.append(frames[at & (index["kind"] == "sample")].mean() - dark)
    return np.array(means)


def _calibrate(capture, out, options, show_progress) -> Outcome:
    out = Path("white.json") if out is None else out
    white = _mean_signal(capture)
    out.write_text(json.dumps({"white_dn": white.tolist()}))
    return Outcome("flat-field calibration", {"calibration": str(out), "bands": len(white)})


def _process(capture, calibration, out, options, show_progress) -> Outcome:
    white = np.array(json.loads(Path(calibration).read_text())["white_dn"])
    reflectance = WHITE * _mean_signal(capture) / white
    up = np.array([[0.0, 0.0, 1.0]])
    btf = BTFStore.create(
        out,
        light_dirs=up,
        view_dirs=up,
        texels=PIXELS,
        grid=WavelengthGrid(BANDS_NM),
        material="moderate red",
        rig=capture.rig_attrs(RigAttrs).rig,
    )
    btf.write_pair(0, np.broadcast_to(reflectance, (PIXELS, PIXELS, BANDS_NM.size)))
    return Outcome("flat-field processing", {"btf": str(out), "complete": btf.complete})


def _evaluate(btf: Path, spp: int, figure: Path | None) -> Outcome:
    measured = BTFStore.open(btf).read()[0].mean(axis=(0, 1))
    error = np.abs(measured - _truth()) / _truth()
    return Outcome("flat-field vs the patch", {"max_relative_error": float(error.max())})


class _Nothing(StrictModel):
    """A rig with no rig file."""


def _flat_field_kind() -> RigKind:
    def program(name: str, reflectance: np.ndarray) -> ProgramKind:
        return ProgramKind(
            name,
            ProgramSettings,
            lambda settings, fault_rate, dry_run: (
                _Program(name, reflectance, settings.seed),
                {},
            ),
            lambda capture: ProgramSettings(seed=capture.metadata.seed),
        )

    def refuse(*_: Any) -> Outcome:
        raise AssertionError("not used")

    return RigKind(
        name=NAME,
        config=_Nothing,
        programs=(
            program("white", np.full(BANDS_NM.size, WHITE)),
            program("patch", _truth()),
        ),
        calibrate=_calibrate,
        process=_process,
        evaluate=_evaluate,
        estimate=refuse,
        sweep=SweepKind(_Nothing, _Nothing, {}, refuse, refuse),
    )


@pytest.fixture
def flat_field():
    kind = register(_flat_field_kind())
    yield kind
    unregister(NAME)


def _invoke(*arguments: object) -> dict:
    result = runner.invoke(app, [str(argument) for argument in arguments])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_a_rig_kind_defined_here_is_captured_calibrated_processed_and_evaluated(
    flat_field, tmp_path
):
    white_store, patch_store = tmp_path / "white.capture.zarr", tmp_path / "patch.capture.zarr"
    for store, name in ((white_store, "white"), (patch_store, "patch")):
        program = rig_kind(NAME).program(name)
        built, _ = program.build(program.settings(seed=3), 0.0, False)
        assert built.run(store).complete
    captured = CaptureStore.open(patch_store)
    assert capture_program(captured)[1].name == "patch"
    assert capture_program(captured)[1].stored(captured).seed == 3

    calibration = tmp_path / "white.json"
    _invoke("calibrate", white_store, "--out", calibration, "--json")
    refused = runner.invoke(app, ["calibrate", str(white_store), "--white-fill", "0.5"])
    assert refused.exit_code == 2 and "--white-fill is not used by a flat-field" in refused.stderr
    btf = tmp_path / "patch.btf.zarr"
    _invoke("process", patch_store, "--calibration", calibration, "--out", btf, "--json")
    assert BTFStore.open(btf).metadata.rig == NAME
    evaluation = _invoke("evaluate", btf, "--json")

    # photon noise of the mean over the window: the white's and the patch's, relative
    electrons = ELECTRONS_PER_S * EXPOSURE_S * _truth() * PIXELS**2
    noise = np.sqrt(1 / electrons + 1 / (ELECTRONS_PER_S * EXPOSURE_S * WHITE * PIXELS**2))
    assert evaluation["max_relative_error"] < 5 * noise.max() + 0.005


def test_the_registry_knows_the_builtin_rigs_and_refuses_an_unknown_one():
    assert {kind.name for kind in (rig_kind("gonioreflectometer"), rig_kind("dome"))} == {
        "gonioreflectometer",
        "dome",
    }
    with pytest.raises(Exception, match="rig: expected one of"):
        rig_kind("flatbed-scanner")
