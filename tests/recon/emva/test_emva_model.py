"""EMVA 1288 pieces of recon.emva: the OECF knee the fit and the twin share, descriptors
written and read back, and what the fit takes to clip first."""

import math

import numpy as np
import pytest

from recon.emva import fit
from recon.emva.descriptor import read_descriptor, read_frame
from recon.emva.linear_model import knee_oecf, knee_oecf_slope, predicted_saturation_e


@pytest.mark.parametrize("strength", [0.0, 0.022, 0.3])
def test_the_knee_keeps_zero_and_the_adc_top_and_scales_noise_by_its_slope(strength):
    top = 4080.0
    assert knee_oecf(np.array([0.0, top]), top, strength) == pytest.approx([0.0, top])
    signal = np.linspace(0.0, top, 9)
    step = 1e-3
    numeric = knee_oecf(signal + step, top, strength) - knee_oecf(signal - step, top, strength)
    assert knee_oecf_slope(signal[1:], top, strength) == pytest.approx(
        numeric[1:] / (2 * step), rel=1e-6
    )
    # Below zero (negative read noise in the dark) the curve goes on with its slope at zero.
    assert knee_oecf(np.array([-10.0]), top, strength) == pytest.approx(-10.0 * (1 + strength))
    assert knee_oecf_slope(np.array([0.0]), top, strength) == pytest.approx(1 + strength)


def test_a_written_measurement_reads_back_step_by_step(tmp_path, make_emva_measurement):
    written = make_emva_measurement(tmp_path, size=16, spatial_frames=4)
    read = read_descriptor(written.path)
    assert (read.bit_depth, read.width, read.height) == (14, 16, 16)
    assert [(s.kind, s.exposure_ns, s.photons, s.images) for s in read.steps] == [
        (s.kind, s.exposure_ns, s.photons, s.images) for s in written.steps
    ]
    assert sum(step.spatial for step in read.steps) == 2 and read.frame_count == 36 * 4 + 8
    frame = read_frame(read.image_path(read.steps[0].images[0]), bit_depth=14, shape=(16, 16))
    assert frame.dtype == np.uint16 and 100 < frame.mean() < 2**14 - 1


def test_the_official_set_002_descriptor_reads_with_its_exposure_0_steps(
    tmp_path, emva_reference_sets
):
    """EMVA1288/datasets ReferenceSet_002 (8-bit CMOS) starts both series at exposure time 0
    (``b 000.00 000.35``, ``d 000.00``), as the emva1288 package reads it."""
    read = emva_reference_sets.read_plan_002(tmp_path)
    assert (read.bit_depth, read.width, read.height, read.version) == (8, 2048, 512, "3.0")
    bright = [step for step in read.steps if step.kind == "bright" and not step.spatial]
    dark = [step for step in read.steps if step.kind == "dark" and not step.spatial]
    assert len(bright) == len(dark) == 100
    assert (bright[0].exposure_ns, bright[0].photons) == (0.0, 0.35) and dark[0].exposure_ns == 0
    spatial = [step for step in read.steps if step.spatial]
    assert [(s.kind, s.exposure_ns, len(s.images)) for s in spatial] == [
        ("bright", 140.0, 100),
        ("dark", 140.0, 100),
    ]
    # A camera makes the 0 ns steps at its shortest exposure: they leave the range it needs.
    assert read.exposure_range_s == pytest.approx((40e-9, 3960e-9))


def _cmos8_model():
    """The fit's model of an 8-bit camera whose ADC clips first: 0.033 DN/e-, 0.2 DN read
    noise, 1.5 % PRNU, 248.7 DN above the offset (7536 e-; the twin's reference set 002 camera,
    ``scripts/emva1288_reference_sets.py``)."""
    return fit._Model(
        gain=0.033,
        responsivity=0.0165,
        knee=0.0,
        dark_rate=0.0,
        read_dn=0.2,
        offset=6.3,
        top=248.7,
        offset_sigma=0.25,
        prnu=0.015,
        max_dn=255,
    )


def test_a_variance_peak_measured_one_step_early_is_still_the_adcs():
    """Of two plan steps that straddle the predicted ADC peak, either may measure the larger
    variance (the curve is flat at its top): the ADC is found clipping first from both, a full
    well only from a peak two steps early, which it then puts at that step."""
    model = _cmos8_model()
    peak_e = predicted_saturation_e(
        math.inf, gain_dn_per_e=0.033, read_noise_dn=0.2, prnu=0.015, adc_top_dn=248.7
    )
    assert model.saturation_e(math.inf) == peak_e
    steps_e = peak_e + 120.0 * np.arange(-4, 4) - 10.0  # the peak 10 e- above a step
    for measured in (steps_e[4], steps_e[3]):  # the step below the peak and the one before it
        full_well, saturated_by = fit._saturation(model, steps_e, float(measured), "test")
        assert saturated_by == "ADC"
        top_e = model.top / model.gain  # 7536 e-: the full well hidden 5 shot-noise widths above
        assert full_well == pytest.approx(top_e + 5 * math.sqrt(top_e), rel=1e-9)
    full_well, saturated_by = fit._saturation(model, steps_e, float(steps_e[2]), "test")
    assert saturated_by == "full well"
    assert model.saturation_e(full_well) == pytest.approx(steps_e[2], abs=0.01)
