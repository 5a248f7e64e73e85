"""What the twin's capture programs write into a capture store reads back as the models of
``hwbridge.schema``: the rig attribute of each kind and program, the plan step by step, and the
settings a resumed capture continues with."""

from __future__ import annotations

import numpy as np
import pytest

from hwbridge.schema import DomeRigAttrs, GonioRigAttrs, RigAttrs
from hwbridge.store import CaptureStore
from recon.spectra import DEFAULT_GRID
from twin.dome.programs import (
    DomeCaptureSize,
    dome_calibration_program,
    dome_run_program,
    stored_dome_settings,
)
from twin.gonio.capture import gonio_calibration_program, gonio_measurement_program
from twin.gonio.sim_session import demo_program
from twin.kinds.registry import capture_program

SIZE = DomeCaptureSize(stage_positions=1, leds=3, rgb_cameras=2, texels=8, spp=4)
PROGRAMS = {
    "demo": lambda: demo_program(4),
    "gonio-calibration": lambda: gonio_calibration_program(pixels=32, seed=4),
    "gonio-run": lambda: gonio_measurement_program(
        np.full(DEFAULT_GRID.size, 2 / 15), pixels=64, window=48, spp=2, seed=4
    ),
    "dome-calibration": lambda: dome_calibration_program(size=SIZE, dark_frames=2, seed=4),
    "dome-run": lambda: dome_run_program("lego", size=SIZE, seed=4),
}
MODELS = {"gonioreflectometer": GonioRigAttrs, "dome": DomeRigAttrs}


def _stored(program, path) -> CaptureStore:
    """A store created for ``program`` (nothing captured), opened again."""
    cameras = {name: camera.frame_shape for name, camera in program.devices().cameras.items()}
    CaptureStore.create(
        path, rig=program.rig, backend="sim", seed=program.seed, plan=program.plan, cameras=cameras
    )
    return CaptureStore.open(path)


@pytest.mark.parametrize("name", PROGRAMS)
def test_a_programs_store_reads_back_as_the_models(tmp_path, name):
    program = PROGRAMS[name]()
    store = _stored(program, tmp_path / f"{name}.capture.zarr")
    model = MODELS[program.rig.rig]
    assert store.rig_attrs(model) == program.rig
    assert store.attrs["rig"] == program.rig.stored()
    assert store.rig_attrs(RigAttrs).program == name
    metadata = store.metadata
    assert metadata.seed == 4 and metadata.backend == "sim"
    assert [step.model_dump(exclude_unset=True) for step in metadata.plan] == program.plan
    kind, stored = capture_program(store)
    assert (kind.name, stored.name) == (program.rig.rig, name)
    assert stored.stored(store).seed == 4


def test_the_fields_of_one_program_only_are_set_by_it(tmp_path):
    calibration = PROGRAMS["dome-calibration"]().rig
    run = PROGRAMS["dome-run"]().rig
    assert (calibration.dark_frames, calibration.material, calibration.stage_positions) == (
        2,
        None,
        None,
    )
    assert (run.dark_frames, run.material, run.stage_positions) == (None, "lego", 1)
    assert run.sample_size_m > 0 and set(run.geometry.cameras) == {"rgb00", "rgb10", "spectral"}
    assert run.geometry.cameras["rgb10"].arc_index == 10
    assert run.geometry.cameras["spectral"].arc_index is None
    store = _stored(PROGRAMS["dome-run"](), tmp_path / "run.capture.zarr")
    assert stored_dome_settings(store) == {
        "program": "dome-run",
        "seed": 4,
        "stage_positions": 1,
        "leds": 3,
        "rgb_cameras": 2,
        "texels": 8,
        "spp": 4,
        "led_renders": "pose",
        "material": "lego",
    }
    demo, gonio_run = PROGRAMS["demo"]().rig, PROGRAMS["gonio-run"]().rig
    assert demo.config is None and demo.light_dirs is None
    assert gonio_run.sensor_px == 64 and gonio_run.window_px == 48 and gonio_run.spp == 2
    assert len(gonio_run.light_dirs) == len(gonio_run.expected_corners_xy)
    assert gonio_run.rings == ((0.0, 1), (30.0, 4), (60.0, 8))
