"""The dome study's store path (:mod:`twin.studies.dome_stores`) end to end on a tiny rendered
capture: a ``dome-run`` of the colour checker (one stage position, LEDs 0 and 197, the RGB
cameras at 0, 37.5 and 75 degrees, 16 texels) and the dark and white frames of its calibration,
written into capture stores, read back, and compared with the analytic path taking the same
images (same LEDs, views, bands and calibration curves)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from skimage.registration import phase_cross_correlation

from recon.scheduling.dome_schedule import THESIS_RGB_EXPOSURES_S
from twin.dome.capture_study import simulate_capture
from twin.dome.programs import DomeCaptureSize
from twin.dome.setup import dome_setup
from twin.studies.dome import STORE_TEXEL_PX, _reference_exposures, multi_image_from_stores
from twin.studies.dome_stores import capture_study_stores, store_capture, store_exposure_ratio

pytestmark = pytest.mark.render

SIZE = DomeCaptureSize(stage_positions=1, leds=2, rgb_cameras=3, texels=16)
TEXELS = SIZE.texels // 2  # the study's texels: 2 x 2 Bayer quads each
SEED = 3


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    folder = tmp_path_factory.mktemp("dome_study")
    return capture_study_stores(folder, "colorchecker16", SIZE, seed=SEED, dark_frames=4)


@pytest.fixture(scope="module")
def setup():
    return dome_setup(TEXELS, texel_px=STORE_TEXEL_PX, seed=SEED)


def test_store_images_match_the_analytic_images_from_the_top(stores, setup):
    """The top camera (rgb00) sees the sample head-on: its rectified images lie on the truth's
    texels within 0.25 texel (phase correlation; measured 0.05-0.1) and their mean V per
    channel within 3 % of the analytic path's (measured 0.3-2.1 %: the renders' 1.5 % patch
    scatter at 64 spp, the white frames' shot noise). The 37.5 and 75 degree cameras are not
    held to it: each is divided by the white standard as that camera sees it (rendered, not
    Lambertian at grazing views) where the analytic path assumes the white's value facing the
    LED (measured +1 to +17 % at 37.5 degrees, up to +51 % at 75 degrees, where the material
    shrinks to a quarter of its width)."""
    images = store_capture(setup, *stores, TEXELS)
    analytic = simulate_capture(
        setup, images.truth, images.light_dirs, images.bands_per_image, np.random.default_rng(0)
    )
    assert images.cameras == ["rgb05"] * 2 + ["rgb00"] * 2 + ["rgb10"] * 2
    assert [len(b) > 0 for b in images.bands_per_image] == [True] * 2 + [False] * 4
    truth_rgb = images.capture.truth @ setup.response
    for image in (2, 3):
        store, model = images.capture.rgb[image], analytic.rgb[image]
        shift, *_ = phase_cross_correlation(
            truth_rgb[image][..., 1], store[..., 1], upsample_factor=20
        )
        assert np.abs(shift).max() < 0.25, shift
        np.testing.assert_allclose(store.mean((0, 1)), model.mean((0, 1)), rtol=0.03)


def test_multi_image_from_stores_reports_both_paths(stores, setup):
    """Both paths reconstruct the same six images; the analytic path's errors are the thesis's
    simulation (measured 16.6 % with bands), the stores' are larger (measured 53.6 % with bands,
    LED 197 at 80 degrees and the 75 degree camera in the joint reconstruction; 29.0 % against
    17.9 % for the top camera, whose texels at 8 across hold a colour-checker field border each,
    where a tenth of a texel of registration moves a texel's value by tens of percent)."""
    result = multi_image_from_stores(setup, *stores, TEXELS, np.random.default_rng(SEED))
    assert result["images"]["paired_camera"] == "rgb05"
    for source in ("stores", "analytic"):
        for group in ("with_spectral_data", "without_spectral_data", "rgb00", "rgb10"):
            assert math.isfinite(result[source][group]["mean_relative_error_pct"])
    analytic = result["analytic"]["rgb00"]["mean_relative_error_pct"]
    assert analytic < result["stores"]["rgb00"]["mean_relative_error_pct"] < 4 * analytic


def test_store_exposure_totals_are_thesis_10_5(stores, setup):
    """10.5 from the stores: the reference exposures from the calibration store's white frames
    through every band against the analytic path's (:func:`twin.studies.dome._reference_exposures`,
    the camera model's white rates), within 2 % (measured 0.5 %: the white's render scatter and
    shot noise over the 8 x 8 patch); the hybrid total is the stored HDR set plus the stored band
    exposures; about 1.5 orders of magnitude apart, as the thesis found (226 s against 7.5 s)."""
    ratio = store_exposure_ratio(*stores, max_dn=setup.cameras.spectral.max_dn)
    hybrid = sum(THESIS_RGB_EXPOSURES_S) + float(setup.exposures_s.sum())
    reference = float(_reference_exposures(setup).sum())
    assert ratio["reference_total_s"] == pytest.approx(reference, rel=0.02)
    assert ratio["hybrid_total_s"] == pytest.approx(hybrid, rel=0.02)
    assert ratio["orders_of_magnitude"] == pytest.approx(math.log10(reference / hybrid), abs=0.02)
    assert 1.3 < ratio["orders_of_magnitude"] < 1.7
