"""The capture store's metadata models (hwbridge.schema): what the store writes, it reads back as
the models; a store of another schema version is refused in one line."""

import pytest
import zarr

from hwbridge.dome_layout import ALL_LEDS
from hwbridge.errors import InputError
from hwbridge.plans import dark_series, gonio_sample_run, plan_step
from hwbridge.replay import ingest
from hwbridge.schema import (
    NO_LIGHT,
    NO_VIEW,
    SCHEMA_VERSION,
    GonioRigAttrs,
    PlanStep,
    ReplayRigAttrs,
    RigAttrs,
    parse,
)
from hwbridge.store import CaptureStore
from recon.measured_data import data_path

PLAN = [
    *dark_series("k4", [0.1], frames_per_exposure=2),
    *gonio_sample_run("k4", [0, 1], [450.0, 550.0], [0.2, 0.4]),
    plan_step("rgb00", "alignment", 0.05, view_id=3, light_id=ALL_LEDS),
    plan_step("spectral", "geometric", 0.5, view_id=0, light_id=ALL_LEDS, tilt_deg=30.0),
]
DEMO = GonioRigAttrs(
    rig="gonioreflectometer",
    program="demo",
    camera="coolsnap_k4",
    camera_id="k4",
    window_px=4,
    lamp="hmi",
)


def _store(path, plan=PLAN, rig=DEMO):
    cameras = {step["camera"]: (4, 4) for step in plan}
    return CaptureStore.create(path, rig=rig, backend="sim", seed=3, plan=plan, cameras=cameras)


def test_the_stored_attributes_read_back_as_the_models(tmp_path):
    store = CaptureStore.open(_store(tmp_path / "run.capture.zarr").path)
    metadata = store.metadata
    assert metadata.schema_version == SCHEMA_VERSION and metadata.seed == 3
    assert metadata.backend == "sim" and not metadata.complete
    assert [step.model_dump(exclude_unset=True) for step in metadata.plan] == PLAN
    # The plan is stored as the builders made it: a step keeps the settings it was given.
    assert store.attrs["plan"] == PLAN
    dark, sample = metadata.plan[0], metadata.plan[2]
    assert (dark.light_id, dark.view_id, dark.band_nm) == (NO_LIGHT, NO_VIEW, None)
    assert (sample.view_id, sample.band_nm, sample.light_id) == (0, 450.0, 0)
    assert metadata.plan[-1].tilt_deg == 30.0
    assert store.rig_attrs(GonioRigAttrs) == DEMO
    assert store.rig_attrs(RigAttrs).program == "demo"


def test_a_step_or_rig_that_does_not_fit_is_refused_in_one_line(tmp_path):
    with pytest.raises(InputError) as refused:
        _store(tmp_path / "a.zarr", plan=[{**PLAN[0], "kind": "selfie"}])
    message = str(refused.value)
    assert "capture store attributes: plan.0.kind: Input should be 'dark'" in message
    assert "\n" not in message and not (tmp_path / "a.zarr").exists()
    with pytest.raises(InputError, match=r"plan\.0\.shutter: Extra inputs are not permitted"):
        _store(tmp_path / "b.zarr", plan=[{**PLAN[0], "shutter": "open"}])
    store = _store(tmp_path / "c.zarr", rig={"rig": "gonioreflectometer", "program": "demo"})
    with pytest.raises(InputError, match=r"c\.zarr: rig attribute: camera: Field required"):
        store.rig_attrs(GonioRigAttrs)
    with pytest.raises(InputError, match="^rig: program gonio-run records config, "):
        parse(GonioRigAttrs, DEMO.stored() | {"program": "gonio-run"}, "rig")


@pytest.mark.parametrize(("version", "shown"), [(0, "0"), ("1", "'1'"), (None, "none recorded")])
def test_a_store_of_another_schema_version_is_refused_in_one_line(tmp_path, version, shown):
    path = _store(tmp_path / "run.capture.zarr").path
    group = zarr.open_group(str(path), mode="r+")
    if version is None:
        del group.attrs["schema_version"]
    else:
        group.attrs["schema_version"] = version
    with pytest.raises(InputError) as refused:
        CaptureStore.open(path)
    assert str(refused.value) == (
        f"{path}: a capture store of schema version {shown}, expected {SCHEMA_VERSION} (written "
        "by another version of the software)"
    )


def test_a_replayed_capture_records_its_mapping_as_its_rig(tmp_path):
    store = ingest(data_path("real/llanos2019"), "llanos2019", tmp_path / "l.capture.zarr")
    rig = store.rig_attrs(ReplayRigAttrs)
    assert (rig.rig, rig.program, rig.bit_depth) == ("replay", "llanos2019", 8)
    steps = store.metadata.plan
    assert steps[0].file.endswith(".tif") and {step.kind for step in steps} == {"dark", "chart"}


def test_a_mapping_whose_rig_does_not_fit_is_refused(tmp_path):
    mapping = tmp_path / "m.yaml"
    mapping.write_text("camera: c\nrig:\n  bitdepth: 8\nfiles:\n  - pattern: 'x'\n    kind: dark\n")
    with pytest.raises(InputError, match=r"m\.yaml: rig: bitdepth: Extra inputs"):
        ingest(tmp_path, mapping, tmp_path / "x.capture.zarr")


def test_a_plan_step_reads_unset_settings_as_none_and_keeps_them_unset():
    step = PlanStep.model_validate({"camera": "k4", "kind": "white", "exposure_s": 1.0})
    assert (step.light_id, step.view_id, step.band_nm, step.tilt_deg) == (-1, -1, None, None)
    assert step.model_dump(exclude_unset=True) == {
        "camera": "k4",
        "kind": "white",
        "exposure_s": 1.0,
    }
    with pytest.raises(ValueError, match="greater than 0"):
        PlanStep(camera="k4", kind="dark", exposure_s=0.0)
