"""The dome's capture plans (thesis 10.2-10.4) and their timing, cameras in parallel."""

import pytest

from hwbridge.dome_layout import ALL_LEDS, camera_steps, rgb_camera_id
from hwbridge.dome_plans import (
    DomeCameraIds,
    DomeExposures,
    DomeTiming,
    dome_calibration,
    dome_duration_s,
    dome_run,
    dome_start_times_s,
)
from hwbridge.errors import InputError
from hwbridge.schema import PlanStep

HDR = (0.05, 0.186, 0.666, 2.5)  # thesis 10.4
CAMERAS = DomeCameraIds((rgb_camera_id(0), rgb_camera_id(6)), "spectral")
EXPOSURES = DomeExposures(
    rgb_hdr_s=HDR,
    bands_nm=(450.0, 550.0, 650.0),
    band_s=(5.0, 1.0, 2.0),
    schedule=((0,), (1, 2)),
    all_leds_s={"rgb00": 0.01, "rgb06": 0.01, "spectral": 0.1},
    rgb_series_s=(0.001, 0.01, 0.1),
    spectral_series_s=(0.5, 1.0),
)
TIMING = DomeTiming(3.0, 0.01, {"rgb00": 0.0625, "rgb06": 0.0625, "spectral": 0.13})


def test_the_run_takes_per_stage_position_an_alignment_set_then_hdr_sets_and_scheduled_bands():
    plan = dome_run(CAMERAS, EXPOSURES, stage_positions=[0, 1], leds=[5, 7, 9])
    alignment = [step for step in plan if step["kind"] == "alignment"]
    assert [(s["camera"], s["view_id"], s["light_id"]) for s in alignment] == [
        (camera, view, ALL_LEDS) for view in (0, 1) for camera in ("rgb00", "rgb06", "spectral")
    ]
    for camera in CAMERAS.rgb:
        samples = [s for s in plan if s["camera"] == camera and s["kind"] == "sample"]
        assert [s["exposure_s"] for s in samples] == list(HDR) * 6  # 2 positions x 3 LEDs
        assert [s["light_id"] for s in samples[::4]] == [5, 7, 9, 5, 7, 9]
        assert all("band_nm" not in s for s in samples)
    # LED k of the run, counted over the positions, gets schedule image k mod 2
    bands = [
        (s["view_id"], s["light_id"], s["band_nm"], s["exposure_s"])
        for s in plan
        if s["camera"] == "spectral" and s["kind"] == "sample"
    ]
    assert bands == [
        (0, 5, 450.0, 5.0),
        (0, 7, 550.0, 1.0),
        (0, 7, 650.0, 2.0),
        (0, 9, 450.0, 5.0),
        (1, 5, 550.0, 1.0),
        (1, 5, 650.0, 2.0),
        (1, 7, 450.0, 5.0),
        (1, 9, 550.0, 1.0),
        (1, 9, 650.0, 2.0),
    ]
    steps = [PlanStep.model_validate(step) for step in plan]
    assert camera_steps(steps, "spectral")[0] == 2  # the spectral alignment frame


def test_the_calibration_has_dark_series_response_series_charts_white_and_geometric_frames():
    plan = dome_calibration(
        CAMERAS,
        EXPOSURES,
        leds=[5, 7],
        calibration_led=3,
        geometric_views=[(0, 0.0), (6, 20.0)],
        dark_frames=200,
        rgb_dark_frames=4,
    )
    kinds = [step["kind"] for step in plan]
    assert kinds == sorted(kinds, key=["dark", "oecf", "chart", "white", "geometric"].index)
    darks = [s for s in plan if s["kind"] == "dark"]
    spectral_times = {s["exposure_s"] for s in darks if s["camera"] == "spectral"}
    # every exposure the spectral camera makes: bands, response series, all-LED frames
    assert spectral_times == {5.0, 1.0, 2.0, 0.5, 0.1}
    for time in spectral_times:
        assert sum(s["camera"] == "spectral" and s["exposure_s"] == time for s in darks) == 200
    assert sum(s["camera"] == "rgb06" for s in darks) == 4 * 5  # HDR set + all-LED exposure
    oecf = [s for s in plan if s["kind"] == "oecf"]
    assert {s["light_id"] for s in oecf} == {3}
    assert [s["exposure_s"] for s in oecf if s["camera"] == "spectral"] == [0.5, 1.0]
    assert {s["band_nm"] for s in oecf if s["camera"] == "spectral"} == {550.0}
    chart = [s for s in plan if s["kind"] == "chart"]  # every RGB camera's HDR set, no bands
    assert [(s["camera"], s["exposure_s"]) for s in chart] == [
        (camera, t) for camera in CAMERAS.rgb for t in HDR
    ]
    assert {s["light_id"] for s in chart} == {3} and {s["view_id"] for s in chart} == {0}
    white = [s for s in plan if s["kind"] == "white"]
    for led in (5, 7):  # every RGB camera's HDR set and the spectral reference band per LED
        lit = [s for s in white if s["light_id"] == led]
        assert len(lit) == 2 * 4 + 1 and lit[-1]["band_nm"] == 550.0
    bandwise = [s for s in white if s["light_id"] == 3]
    assert [(s["band_nm"], s["exposure_s"]) for s in bandwise] == [
        (450.0, 5.0),
        (550.0, 1.0),
        (650.0, 2.0),
    ]
    geometric = [s for s in plan if s["kind"] == "geometric"]
    assert [(s["view_id"], s["tilt_deg"]) for s in geometric[::3]] == [(0, 0.0), (6, 20.0)]
    assert {s["light_id"] for s in geometric} == {ALL_LEDS}


def test_cameras_expose_in_parallel_and_a_slot_ends_with_its_slowest_camera():
    plan = dome_run(CAMERAS, EXPOSURES, stage_positions=[0], leds=[5, 7])
    starts = dome_start_times_s(plan, TIMING)
    # turn the stage, switch all LEDs on; the spectral frame is the slowest
    alignment_end = 3.0 + 0.01 + 0.1 + 0.13
    rgb_chain = sum(HDR) + 4 * 0.0625
    led5 = alignment_end + 0.01  # switch the LED
    assert starts[3] == pytest.approx(led5)  # rgb00's first exposure
    assert starts[7] == pytest.approx(led5)  # rgb06 in parallel
    assert starts[11] == pytest.approx(led5)  # the spectral camera too
    assert starts[4] == pytest.approx(led5 + 0.05 + 0.0625)
    led7 = led5 + max(rgb_chain, 5.0 + 0.13) + 0.01  # the 450 nm band (5 s) outlasts the HDR set
    assert starts[12] == pytest.approx(led7)
    end = led7 + max(rgb_chain, 1.0 + 2.0 + 2 * 0.13)
    assert dome_duration_s(plan, TIMING) == pytest.approx(end)


def test_bad_plans_are_refused():
    with pytest.raises(InputError, match="every band index"):
        DomeExposures(HDR, (450.0, 550.0), (1.0, 2.0), ((0,),), {})
    with pytest.raises(InputError, match="distinct"):
        dome_run(CAMERAS, EXPOSURES, stage_positions=[0, 0], leds=[1])
    with pytest.raises(InputError, match="distinct ids"):
        DomeCameraIds(("spectral",), "spectral")
    with pytest.raises(InputError, match="no frame overhead"):
        dome_duration_s(
            dome_run(CAMERAS, EXPOSURES, stage_positions=[0], leds=[1]),
            DomeTiming(1.0, 0.0, {"rgb00": 0.1}),
        )
