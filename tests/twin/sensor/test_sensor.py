"""Sensor model (twin.sensor.model): EMVA 1288 photon transfer with the emva1288 package as peer,
dark frames, lamp flicker, Bayer mosaic, OECF, determinism and bad input."""

import math

import numpy as np
import pytest
from emva1288.process.data import Data1288
from emva1288.process.routines import get_int_imgs
from scipy import constants

from recon.emva.analysis import run_results1288
from recon.errors import InputError
from recon.radiometric.demosaic import demosaic
from recon.spectra import SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID, HMILamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.rigs.camera_config import load_camera_config
from twin.sensor import model as sensor_model
from twin.sensor.model import Sensor, bayer_channel_index, shot_electrons
from twin.sensor.white_reference import white_reference_rates

WAVELENGTH_NM = 550.0
VS10_BANDS = LiquidCrystalTunableFilter.varispec("VS-10").transmission(FINE_GRID)


def white_target_part_rates(sensor, lamp, band_nm):
    """Photo-electrons per second of each lamp part: Zenith white, HMI at 2 m, one VS-10 band."""
    band = VS10_BANDS.row(f"lctf_{band_nm:g}nm")
    return white_reference_rates(sensor, lamp, band, distance_m=2.0)[:, 0]


def _photons_per_pixel(sensor: Sensor, irradiance_w_m2: float, exposure_s: float) -> float:
    """EMVA 1288 Eq. (2): mu_p = A E t lambda / (h c), computed here independently."""
    return (
        sensor.pixel_area_m2
        * irradiance_w_m2
        * exposure_s
        * WAVELENGTH_NM
        * 1e-9
        / (constants.h * constants.c)
    )


def _temporal_entry(frames):
    pair = get_int_imgs(frames)
    return {"sum": np.sum(pair["sum"]), "pvar": np.sum(pair["pvar"]), "dmean": pair["dmean"]}


@pytest.fixture(scope="module")
def photon_transfer():
    """A flat-field series at 550 nm on a 128x128 window of the K4, analysed by emva1288."""
    sensor = Sensor("coolsnap_k4", roi=(128, 128))
    rng = np.random.default_rng(1288)
    exposure_s = 0.1
    eta = sensor.quantum_efficiency(WavelengthGrid(np.array([WAVELENGTH_NM, 551.0]))).values[0, 0]
    # Irradiance steps up to 115 % of saturation, dense near the top to locate it.
    saturation_irradiance = sensor.saturation_capacity_e / (
        eta * _photons_per_pixel(sensor, 1.0, exposure_s)
    )
    levels = np.concatenate([np.linspace(0.02, 0.9, 30), np.linspace(0.9, 1.15, 60)])
    shape = (sensor.height, sensor.width)

    def frames(irradiance: float, count: int):
        electrons = sensor.electrons_from_monochromatic_irradiance(
            np.full(shape, irradiance), WAVELENGTH_NM, exposure_s
        )
        return [sensor.capture(electrons, exposure_s, rng) for _ in range(count)]

    temporal = {0.0: _temporal_entry(frames(0.0, 2))}
    for level in levels:
        irradiance = level * saturation_irradiance
        temporal[_photons_per_pixel(sensor, irradiance, exposure_s)] = _temporal_entry(
            frames(irradiance, 2)
        )
    half = 0.5 * saturation_irradiance
    spatial = {
        0.0: get_int_imgs(frames(0.0, 16)),
        _photons_per_pixel(sensor, half, exposure_s): get_int_imgs(frames(half, 16)),
    }
    data = Data1288(
        {
            "width": shape[1],
            "height": shape[0],
            "temporal": {exposure_s: temporal},
            "spatial": {exposure_s: spatial},
        }
    )
    return sensor, eta, run_results1288(data.data)  # the package, on NumPy 2 too


def test_emva1288_recovers_the_system_gain(photon_transfer):
    sensor, _, results = photon_transfer
    assert results.K == pytest.approx(sensor.config.system_gain_dn_per_e, rel=0.02)


def test_emva1288_recovers_the_dark_noise(photon_transfer):
    sensor, _, results = photon_transfer
    read_noise_e = sensor.config.read_noise_dn / sensor.config.system_gain_dn_per_e
    dark_e = float(sensor.mean_dark_electrons(0.1).mean())
    assert results.sigma_d == pytest.approx(math.sqrt(read_noise_e**2 + dark_e), rel=0.02)


def test_emva1288_recovers_the_quantum_efficiency(photon_transfer):
    _, eta, results = photon_transfer
    assert results.QE / 100 == pytest.approx(eta, rel=0.02)


def test_emva1288_recovers_the_saturation_capacity(photon_transfer):
    sensor, _, results = photon_transfer
    # EMVA 1288 saturation is the peak of the temporal variance, a few noise widths below the
    # hard clip of the ADC (19975 e- for the K4): compare with the model's prediction of that
    # peak, and check it sits within 3 % below the clip.
    assert results.u_e_sat == pytest.approx(sensor.emva_saturation_capacity_e(), rel=0.02)
    assert 0.97 < sensor.emva_saturation_capacity_e() / sensor.saturation_capacity_e < 1.0


@pytest.mark.parametrize(
    ("camera", "exposures_s"),
    [
        ("coolsnap_k4", [0.001, 1.0, 30.0, 300.0]),
        ("svs_vistek_4022", [0.001, 0.1, 1.0, 10.0]),
    ],
)
def test_dark_frames_follow_the_model(camera, exposures_s):
    sensor = Sensor(camera, roi=(256, 256))
    gain, read_dn = sensor.config.system_gain_dn_per_e, sensor.config.read_noise_dn
    rng = np.random.default_rng(7)
    for exposure_s in exposures_s:
        first, second = (sensor.dark_frame(exposure_s, rng).astype(float) for _ in range(2))
        mean_dark_e = sensor.mean_dark_electrons(exposure_s)
        linear_dn = gain * mean_dark_e.mean()
        expected_mean = sensor.config.adc_offset_dn + sensor.oecf(np.array(linear_dn))
        # Temporal noise from the difference of two frames removes the fixed pattern; the OECF
        # scales it by its local slope.
        slope = sensor.oecf(np.array(linear_dn + 0.5)) - sensor.oecf(np.array(linear_dn - 0.5))
        temporal_std = np.std(first - second) / math.sqrt(2)
        expected_std = math.sqrt(slope**2 * (gain**2 * mean_dark_e.mean() + read_dn**2) + 1 / 12)
        assert np.mean((first + second) / 2) == pytest.approx(expected_mean, rel=0.01, abs=0.05)
        assert temporal_std == pytest.approx(expected_std, rel=0.03)


def test_cooled_k4_has_3_dn_dark_noise_and_almost_no_dark_current():
    sensor = Sensor("coolsnap_k4", roi=(512, 512))
    rng = np.random.default_rng(3)
    first, second = (sensor.dark_frame(0.01, rng).astype(float) for _ in range(2))
    assert np.std(first - second) / math.sqrt(2) == pytest.approx(3.0, rel=0.05)
    assert sensor.dark_current_e_per_s < 0.1
    uncooled = Sensor("svs_vistek_4022")
    assert uncooled.dark_current_e_per_s > 1000 * sensor.dark_current_e_per_s


def test_dark_frames_show_the_shift_direction_gradient_and_hot_pixels():
    sensor = Sensor("coolsnap_k4")
    mean_dark = sensor.mean_dark_electrons(300.0)
    row_medians = np.median(mean_dark, axis=1)
    slope, _ = np.polyfit(np.arange(sensor.height), row_medians, 1)
    rise = slope * (sensor.height - 1)
    assert rise == pytest.approx(sensor.config.fixed_pattern.transfer_dark_e, rel=0.05)
    hot_fraction = np.mean(mean_dark > 50 * np.median(mean_dark))
    assert hot_fraction == pytest.approx(sensor.config.fixed_pattern.hot_pixel_fraction, rel=0.3)


def test_a_window_sees_the_sensors_fixed_patterns_whatever_its_size():
    """The fixed patterns belong to the sensor's pixels (seeded by the serial): a small window
    holds the top-left pixels' values of a larger one, the same serial gives them again, and
    another serial other ones."""
    small, large = Sensor("svs_vistek_4022", roi=(16, 24)), Sensor("svs_vistek_4022")
    for pattern in (
        lambda sensor: sensor._photo_response,
        lambda sensor: sensor._dark_factor,
        lambda sensor: sensor._offsets_and_defects[0],
    ):
        np.testing.assert_array_equal(pattern(small), pattern(large)[:16, :24])
    np.testing.assert_array_equal(small.defect_pixels(), large.defect_pixels()[:16, :24])
    again = Sensor("svs_vistek_4022", roi=(16, 24))
    np.testing.assert_array_equal(again.mean_dark_electrons(1.0), small.mean_dark_electrons(1.0))
    other = Sensor(small.config.model_copy(update={"serial": "another"}), roi=(16, 24))
    assert not np.array_equal(other.mean_dark_electrons(1.0), small.mean_dark_electrons(1.0))


def test_hmi_flicker_spreads_frames_unless_the_exposure_is_a_multiple_of_1_15_s():
    sensor = Sensor("coolsnap_k4", roi=(32, 32))
    lamp = HMILamp()
    rates = white_target_part_rates(sensor, lamp, 550.0)
    gain = sensor.config.system_gain_dn_per_e
    rng = np.random.default_rng(15)
    spreads, predicted = {}, {}
    for exposure_s in (0.050, 1 / 15):
        starts = np.arange(100) * (exposure_s + 0.130)  # 130 ms filter switching and download
        electrons = np.array([lamp.part_exposure_s(t0, exposure_s) @ rates for t0 in starts])
        frames = [
            sensor.capture(np.full((32, 32), mean, np.float32), exposure_s, rng)
            for mean in electrons
        ]
        frame_means = np.array([frame.mean() for frame in frames])
        spreads[exposure_s] = np.std(frame_means, ddof=1)
        noise_var = (gain**2 * electrons.mean() + sensor.config.read_noise_dn**2 + 1 / 12) / 32**2
        predicted[exposure_s] = math.sqrt(np.var(gain * electrons, ddof=1) + noise_var)
    assert spreads[0.050] == pytest.approx(predicted[0.050], rel=0.15)
    assert spreads[1 / 15] == pytest.approx(predicted[1 / 15], rel=0.15)
    assert spreads[0.050] > 5 * spreads[1 / 15]


def test_flicker_is_in_the_line_bands_only():
    sensor = Sensor("coolsnap_k4", roi=(8, 8))
    lamp = HMILamp()
    line_band, continuum_band = (
        white_target_part_rates(sensor, lamp, 550.0),
        white_target_part_rates(sensor, lamp, 650.0),
    )
    assert line_band[1] > 0.1 * line_band[0]
    # Only the LCTF's out-of-band leakage lets line light into a continuum band.
    assert continuum_band[1] < 1e-3 * continuum_band[0]


def test_spectral_and_irradiance_paths_agree():
    """Radiance through the optics (etendue) equals the irradiance path pi tau L / (4 N^2)."""
    sensor = Sensor("coolsnap_k4", roi=(4, 4))
    grid = WavelengthGrid.regular(500, 600, 0.05)
    width = 0.2
    line = np.exp(-0.5 * ((grid.wavelengths_nm - WAVELENGTH_NM) / width) ** 2) / (
        width * math.sqrt(2 * math.pi)
    )
    radiance_exposure = SampledSpectra(grid, 0.3 * line)  # 0.3 J m^-2 sr^-1 concentrated at 550 nm
    spectral = sensor.mean_electrons(radiance_exposure)[0]
    optics = sensor.config.optics
    irradiance = math.pi * optics.transmission * 0.3 / (4 * optics.f_number**2)  # J m^-2 over 1 s
    direct = sensor.electrons_from_monochromatic_irradiance(
        np.full((4, 4), irradiance), WAVELENGTH_NM, 1.0
    )
    assert spectral == pytest.approx(direct[0, 0], rel=1e-3)


def test_same_seed_gives_the_same_frame_and_another_seed_another():
    sensor = Sensor("svs_vistek_4022", roi=(64, 96))
    electrons = np.full((64, 96, 3), 2000.0)
    first = sensor.capture(electrons, 0.01, np.random.default_rng(42))
    again = sensor.capture(electrons, 0.01, np.random.default_rng(42))
    other = sensor.capture(electrons, 0.01, np.random.default_rng(43))
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)


@pytest.mark.parametrize("roi", [(16, 16), (256, 320)])
def test_a_frame_is_the_same_drawn_on_the_calling_thread_or_on_the_pool(monkeypatch, roi):
    """Small frames skip the threads that draw row blocks (``_POOL_MIN_PIXELS``); the blocks and
    their generators are the same, so the same seed gives the same frame either way."""
    sensor = Sensor("svs_vistek_4022", roi=roi)
    electrons = np.full((*roi, 3), 30.0)
    frames = []
    for smallest in (0, 10**9):
        monkeypatch.setattr(sensor_model, "_POOL_MIN_PIXELS", smallest)
        frames.append(sensor.capture(electrons, 0.01, np.random.default_rng(7)))
    np.testing.assert_array_equal(*frames)


def test_bayer_mosaic_is_rggb_and_demosaics_back():
    sensor = Sensor("svs_vistek_4022", roi=(64, 64))
    assert bayer_channel_index(2, 2).tolist() == [[0, 1], [1, 2]]
    red_only = np.zeros((64, 64, 3))
    red_only[..., 0] = 20000.0
    raw = (
        sensor.capture(red_only, 0.001, np.random.default_rng(0)).astype(float)
        - sensor.config.adc_offset_dn
    )
    channel = bayer_channel_index(64, 64)
    assert raw[channel == 0].mean() > 1000 and abs(raw[channel != 0].mean()) < 5
    rgb = demosaic(raw, pattern="RGGB")
    assert rgb.shape == (64, 64, 3)
    assert rgb[8:-8, 8:-8, 0].mean() == pytest.approx(raw[channel == 0].mean(), rel=0.01)


def test_colour_camera_oecf_is_nonlinear_and_the_k4_is_linear():
    rng = np.random.default_rng(9)
    for camera, linear in (("coolsnap_k4", True), ("svs_vistek_4022", False)):
        sensor = Sensor(camera, roi=(64, 64))
        shape = (64, 64, 3) if sensor.is_colour else (64, 64)
        offset = sensor.config.adc_offset_dn
        low, high = (
            sensor.capture(np.full(shape, level * sensor.saturation_capacity_e), 0.01, rng).mean()
            - offset
            for level in (0.2, 0.4)
        )
        assert (high / low == pytest.approx(2.0, rel=0.01)) == linear


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda s: s.capture(np.full((32, 32), 10.0), -0.1, np.random.default_rng()),
            "positive exposure",
        ),
        (lambda s: s.capture(np.full((32, 32), 10.0), 5000.0, np.random.default_rng()), "outside"),
        (lambda s: s.capture(np.full((32, 31), 10.0), 0.1, np.random.default_rng()), "shape"),
        (lambda s: s.capture(np.full((32, 32), np.nan), 0.1, np.random.default_rng()), "NaN"),
        (
            lambda s: s.capture(np.full((32, 32), -1.0), 0.1, np.random.default_rng()),
            "non-negative",
        ),
        (lambda s: s.capture(np.full((32, 32), 1.0), 0.1, 42), "Generator"),
        (
            lambda s: s.electrons_from_monochromatic_irradiance(
                np.full((32, 32), np.nan), 550.0, 0.1
            ),
            "NaN",
        ),
    ],
)
def test_bad_sensor_input_raises_clear_errors(call, message):
    with pytest.raises(InputError, match=message):
        call(Sensor("coolsnap_k4", roi=(32, 32)))


def test_bad_camera_files_name_the_field(tmp_path):
    base = load_camera_config("coolsnap_k4").model_dump_json()
    import json

    document = json.loads(base)
    document["gain_typo"] = 1.0
    del document["read_noise_dn"]
    document["bit_depth"] = 40
    path = tmp_path / "broken.yaml"
    import yaml

    path.write_text(yaml.safe_dump(document))
    with pytest.raises(InputError) as error:
        load_camera_config(path)
    for field in ("gain_typo", "read_noise_dn", "bit_depth"):
        assert field in str(error.value)
    (tmp_path / "bad.yaml").write_text("name: [unclosed\n")
    with pytest.raises(InputError, match="malformed YAML"):
        load_camera_config(tmp_path / "bad.yaml")
    with pytest.raises(InputError, match="coolsnap_k4"):
        load_camera_config("no_such_camera")
    with pytest.raises(InputError, match="roi"):
        Sensor("coolsnap_k4", roi=(4096, 10))


@pytest.mark.parametrize("mean_e", [0.3, 4.0, 9.5, 10.0, 30.0, 300.0, 20000.0])
def test_shot_noise_has_the_poisson_counts_moments(mean_e):
    """Shot noise is counted in whole electrons with the mean, variance and third cumulant of a
    Poisson count (all equal to the mean), below GAUSSIAN_SHOT_E by Poisson draws and from it
    on by a Cornish-Fisher normal approximation; 400 000 pixels, within five standard errors."""
    count = 400_000
    electrons = shot_electrons(np.full(count, mean_e, np.float32), np.random.default_rng(11))
    assert electrons.dtype == np.float32 and np.all(electrons == np.rint(electrons))
    assert electrons.min() >= 0
    centred = electrons.astype(np.float64) - mean_e
    # standard errors of the sample's mean, variance and third moment of a Poisson count
    moments = [centred.mean(), (centred**2).mean() - mean_e, (centred**3).mean() - mean_e]
    errors = [
        math.sqrt(mean_e / count),
        math.sqrt((mean_e + 2 * mean_e**2) / count),
        math.sqrt((mean_e + 24 * mean_e**2 + 15 * mean_e**3) / count),
    ]
    for moment, error in zip(moments, errors, strict=True):
        assert abs(moment) < 5 * error, (moments, errors)
    again = shot_electrons(np.full(count, mean_e, np.float32), np.random.default_rng(11))
    np.testing.assert_array_equal(electrons, again)
