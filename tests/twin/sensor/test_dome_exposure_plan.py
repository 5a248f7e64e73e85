"""The dome's spectral exposure plan with the thesis's parameters, on the twin's components.

Thesis 10.4: 30 bands, 410-700 nm in 10 nm steps, the RGB exposure set 50/186/666/2500 ms,
:math:`t_\\lambda = t_{base} / \\sqrt{E L}`, and a bin-packing schedule: 30 bands in 8 RGB images
at about +41 % total exposure time, 10 RGB images with the noisiest bands taken twice at about
+61 %. Here :math:`E` and :math:`L` come from the twin's dome: the CoolSNAP K4 (QE model of a
KAI-4021) behind the VariSpec VS-10 and the phosphor-white LED, calibrated as in thesis 10.3
(the white reference's response divided by the LED spectrum).

The thesis gives no numbers for Figure 10.5, so :math:`t_{base}` is set from what its text
implies about the longest band: with 10 images at +61 % an image lasts 1.61 x 3.402 s = 5.48 s
on average, and an image cannot be shorter than its longest band, while a packing whose images
are bounded by the longest band (how 8 images come out as the fewest, see
``recon.scheduling.dome_schedule.fewest_images``) cannot average more. So the longest band is set
to 5.48 s. That is a calibration taken from the thesis's +61 %: the tests below check the plan
and the schedules against their closed forms in the band exposures, whatever the longest band,
and one calibration check compares the resulting 10-image increase with the +61 %.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from recon.errors import InputError
from recon.scheduling.dome_schedule import (
    FILTER_SIZE_PER_SIGMA,
    THESIS_RGB_EXPOSURES_S,
    fewest_images,
    filter_sizes,
    schedule_bands,
    spectral_exposures,
)
from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor
from twin.sensor.white_reference import white_reference_rates

BAND_CENTRES_NM = np.arange(410.0, 701.0, 10.0)
RGB_S = sum(THESIS_RGB_EXPOSURES_S)
LONGEST_S = 1.61 * RGB_S  # calibration: from the thesis's +61 % for 10 images (docstring)
GREY = 0.2  # reflectance of the sample whose band images set the filter sizes
TARGET_RELATIVE_NOISE = 0.02


@pytest.fixture(scope="module")
def dome():
    config = load_rig("dome")
    lctf = LiquidCrystalTunableFilter.varispec(
        config.spectral_camera.filter, band_centres_nm=tuple(BAND_CENTRES_NM)
    )
    sensor = Sensor(config.spectral_camera.definition)
    led = PhosphorWhiteLED()
    bands = lctf.transmission(FINE_GRID)
    # Thesis 10.3: the white reference lit by one LED (facing it at the dome's radius), its
    # linearized response divided by the LED's spectrum gives E per band.
    white_rates = white_reference_rates(sensor, led, bands, distance_m=config.radius_m).sum(0)
    light = np.interp(BAND_CENTRES_NM, FINE_GRID.wavelengths_nm, led.intensity(FINE_GRID).values)
    sensitivity = white_rates / light
    base_s = LONGEST_S * math.sqrt((sensitivity * light).min())
    exposures = spectral_exposures(
        base_s, sensitivity, light, limits_s=sensor.config.exposure_range_s
    )
    radiance = SampledSpectra(
        FINE_GRID, GREY * led.intensity(FINE_GRID).values / math.pi / config.radius_m**2
    )
    grey_rates = sensor.mean_electrons(radiance, bands)
    return {
        "sensitivity": sensitivity,
        "light": light,
        "exposures": exposures,
        "grey_rates": grey_rates,
        "sensor": sensor,
    }


def test_exposures_follow_the_thesis_rule_and_the_blue_end_is_longest(dome):
    exposures = dome["exposures"]
    product = dome["sensitivity"] * dome["light"]
    assert np.allclose(exposures * np.sqrt(product), exposures[0] * np.sqrt(product[0]))
    # t_base = t_longest sqrt(min E L): t_lambda = t_longest sqrt(min E L / E L).
    np.testing.assert_allclose(exposures, LONGEST_S * np.sqrt(product.min() / product), rtol=1e-9)
    assert BAND_CENTRES_NM[np.argmax(exposures)] == 410.0  # no LED light, weak LCTF and QE
    assert BAND_CENTRES_NM[np.argmin(exposures)] in (550.0, 560.0, 570.0)  # phosphor peak
    # Some bands are longer than the RGB set (thesis: "some of the exposure times ... are
    # larger than the total RGB exposure time"), most are far shorter.
    assert 1 <= np.count_nonzero(exposures > RGB_S) <= 3
    assert np.median(exposures) < RGB_S / 2


def test_thirty_bands_in_eight_images(dome):
    exposures = dome["exposures"]
    plan = schedule_bands(exposures, 8)
    assert plan.optimal
    assert sorted(b for image in plan.images for b in image) == list(range(30))
    # The bands (measured 47.97 s) exceed 8 x 3.402 s: every image is spectral-bound and the
    # optimum is the band sum itself (measured +76 % where the thesis reports +41 %: its bands
    # sum to about 38 s).
    band_sum = exposures.sum()
    assert band_sum > 8 * RGB_S
    assert plan.total_s == pytest.approx(band_sum, rel=1e-6)
    assert plan.increase == pytest.approx(band_sum / (8 * RGB_S) - 1, rel=1e-6)
    assert plan.image_s.max() < 1.05 * band_sum / 8  # balanced, about 6 s each
    # With images no longer than the longest band, 8 do not suffice: 47.97 / 5.48 > 8.
    with pytest.raises(InputError, match="no schedule of 30 band exposures in 8"):
        schedule_bands(exposures, 8, image_limit_s=exposures.max())
    fewest = fewest_images(exposures)
    assert fewest.n_images == math.ceil(band_sum / exposures.max()) == 9
    assert fewest.optimal
    assert fewest.increase == pytest.approx(band_sum / (9 * RGB_S) - 1, rel=1e-6)  # +56.7 %


def test_ten_images_with_the_noisiest_bands_twice(dome):
    exposures = dome["exposures"]
    noisiest = np.argsort(-exposures)  # longest exposure = least signal (signal ~ sqrt(E L))
    # Repeat as many of the noisiest bands as 10 images (each no longer than the longest band)
    # can hold.
    repeats = 0
    while fewest_images(exposures, repeat_bands=noisiest[: repeats + 1]).n_images <= 10:
        repeats += 1
    assert repeats == 1 and BAND_CENTRES_NM[noisiest[0]] == 410.0
    plan = schedule_bands(
        exposures, 10, repeat_bands=noisiest[:repeats], image_limit_s=exposures.max()
    )
    assert plan.optimal
    holding_410 = [image for image, bands in enumerate(plan.images) if noisiest[0] in bands]
    assert len(holding_410) == 2
    assert plan.total_s == pytest.approx(exposures.sum() + exposures.max(), rel=1e-6)
    assert plan.increase == pytest.approx(
        (exposures.sum() + exposures.max()) / (10 * RGB_S) - 1, rel=1e-6
    )


def test_calibration_check_the_longest_band_gives_about_the_thesis_increase_for_10_images(dome):
    """A calibration check, not a prediction: the longest band was derived from the thesis's
    +61 % (module docstring), so the 10-image schedule lands near it by construction. Measured
    +57.1 %: the twin's other bands are shorter than the thesis's (their sum, 48 s, is the
    model's). How the increase moves with the longest band:
    benchmarks/capture_time_sensitivity.py."""
    exposures = dome["exposures"]
    plan = schedule_bands(
        exposures, 10, repeat_bands=[int(np.argmax(exposures))], image_limit_s=exposures.max()
    )
    assert plan.increase == pytest.approx(0.61, abs=0.05)


def test_filter_sizes_from_simulated_band_images_cancel_their_noise(dome, rng):
    """Figure 10.5's second curve: the filter size per band, from the K4's simulated noise."""
    exposures, rates = dome["exposures"], dome["grey_rates"]
    sensor = Sensor(dome["sensor"].config, roi=(512, 512))
    gain, offset = sensor.config.system_gain_dn_per_e, sensor.config.adc_offset_dn

    def band_image(band: int) -> np.ndarray:
        electrons = np.full((512, 512), rates[band] * exposures[band], np.float32)
        frame = sensor.capture(electrons, float(exposures[band]), rng).astype(np.float64)
        return frame - offset - gain * sensor.mean_dark_electrons(float(exposures[band]))

    images = [band_image(band) for band in range(30)]
    relative_noise = np.array([image.std() / image.mean() for image in images])
    # Shot and read noise: sqrt(mu + (3 DN / 0.2 DN/e)^2) / mu, within the estimate's spread.
    signal = rates * exposures
    expected = np.sqrt(signal + (sensor.config.read_noise_dn / gain) ** 2) / signal
    assert relative_noise == pytest.approx(expected, rel=0.03)
    sizes = filter_sizes(relative_noise, TARGET_RELATIVE_NOISE)
    assert BAND_CENTRES_NM[np.argmax(sizes)] == 410.0
    assert sizes.max() == pytest.approx(32.0, rel=0.05)  # sigma ~ 6.4 px
    assert (
        np.corrcoef(np.argsort(np.argsort(sizes)), np.argsort(np.argsort(exposures)))[0, 1] > 0.97
    )  # the longer the exposure, the noisier the band, the larger the filter
    for band in (0, 15, 29):  # 410, 560, 700 nm
        sigma = sizes[band] / FILTER_SIZE_PER_SIGMA
        filtered = ndimage.gaussian_filter(images[band], sigma)[64:-64, 64:-64]
        assert filtered.std() / filtered.mean() == pytest.approx(TARGET_RELATIVE_NOISE, rel=0.1)
