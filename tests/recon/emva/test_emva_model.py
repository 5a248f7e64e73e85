"""EMVA 1288 pieces of recon.emva: the OECF knee the fit and the twin share, and descriptors
written and read back."""

import numpy as np
import pytest

from recon.emva.descriptor import read_descriptor, read_frame
from recon.emva.linear_model import knee_oecf, knee_oecf_slope


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
