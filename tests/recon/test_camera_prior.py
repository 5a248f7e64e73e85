"""The measured cameras shipped with spectwin, the prior learned from them (recon.camera_prior)
and Jiang et al. 2013 through colour-science (recon.camera_jiang2013)."""

import colour
import numpy as np
import pytest

from recon.camera_char import estimate_response, measured_response_prior
from recon.camera_jiang2013 import jiang2013_response
from recon.camera_prior import learn_response_prior
from recon.errors import InputError
from recon.measured_data import camera_names, read_camera_sensitivities, read_spectra_csv
from recon.metrics import peak_relative_rmse
from recon.spectra import DEFAULT_GRID, WavelengthGrid, from_colour, resample

GRID = WavelengthGrid.regular(380, 780, 10)
WAVELENGTHS = GRID.wavelengths_nm
NAMES = camera_names()
RESPONSES = np.array(
    [
        resample(read_camera_sensitivities(name), GRID, method="box", out_of_range="clamp").values.T
        for name in NAMES
    ]
)


def _reflectances(file_name: str) -> np.ndarray:
    measured = read_spectra_csv(f"spectra/reflectances/{file_name}")
    values = resample(measured, GRID, method="box", out_of_range="clamp").values
    return np.clip(values[values.max(axis=1) <= 1.0], 0, 1)  # diffuse reflectances only


CHART = _reflectances("rawtoaces_training_190.csv")  # the 185 within [0, 1]
COLORCHECKER = _reflectances("macbeth_colorchecker.csv")
DAYLIGHT = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), GRID, method="box").values


def _left_out(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The camera's response and the responses of all the others."""
    index = NAMES.index(name)
    return RESPONSES[index], np.delete(RESPONSES, index, axis=0)


def test_the_51_measured_cameras_read_by_name():
    assert len(NAMES) == 51 and len(set(NAMES)) == 51 and "Nikon D850" in NAMES
    spectra = read_camera_sensitivities("Nikon D850")
    assert spectra.names == ("R", "G", "B") and spectra.values.shape == (3, 81)
    assert (spectra.grid.start_nm, spectra.grid.stop_nm) == (380.0, 780.0)
    np.testing.assert_array_equal(read_camera_sensitivities("Nikon_D850").values, spectra.values)
    assert np.all(RESPONSES >= 0) and np.all(RESPONSES.max(axis=1) > 0)
    # Each channel peaks where a colour filter should: B below G below R.
    peaks = WAVELENGTHS[RESPONSES.argmax(axis=1)]  # (51, 3)
    assert np.all(peaks[:, 2] < peaks[:, 1]) and np.all(peaks[:, 1] < peaks[:, 0])


def test_an_unknown_camera_is_named_with_the_closest_ones():
    with pytest.raises(InputError, match="Nikon D850"):
        read_camera_sensitivities("Nikon D85")


def test_the_prior_is_a_maximum_likelihood_ppca_and_scores_shapes_not_scales():
    truth, others = _left_out("Nikon D850")
    prior = learn_response_prior(others, WAVELENGTHS)
    assert prior.cameras == 50
    # Tipping & Bishop (1999): at the maximum-likelihood fit trace(C^-1 S) = K, S the sample
    # covariance; sklearn's uses N - 1, so the mean Mahalanobis distance is K (N - 1) / N.
    shapes = others / others.max(axis=1, keepdims=True)
    for channel in range(3):
        centred = shapes[:, :, channel] - prior.mean[:, channel]
        distances = np.einsum("nk,kl,nl->n", centred, prior.precision[channel], centred)
        assert distances.mean() == pytest.approx(41 * 49 / 50, rel=1e-9)
    # E_prior: the distance to the nearest multiple of the mean, whatever the scale.
    energy = prior.energy(truth)
    for channel in range(3):
        shape = truth[:, channel] / truth[:, channel].max()
        precision, mean = prior.precision[channel], prior.mean[:, channel]
        scale = (mean @ precision @ shape) / (mean @ precision @ mean)
        residual = shape - scale * mean
        assert energy[channel] == pytest.approx(residual @ precision @ residual, rel=1e-9)
    np.testing.assert_allclose(prior.energy(7.0 * truth), energy, rtol=1e-12)
    np.testing.assert_allclose(prior.energy(3.0 * prior.mean), 0.0, atol=1e-6)


def test_a_camera_unlike_the_others_has_a_high_prior_energy():
    """The Canon PowerShot S90 (a compact camera) lies far from the other 50; a Sony mirrorless
    near them (measured summed energies 1500 and 41; the median over the 51 cameras is 83)."""
    energies = {}
    for name in ("Canon PowerShot S90", "Sony ILCE-7M3"):
        truth, others = _left_out(name)
        energies[name] = learn_response_prior(others, WAVELENGTHS).energy(truth).sum()
    assert energies["Canon PowerShot S90"] > 10 * energies["Sony ILCE-7M3"]
    assert energies["Sony ILCE-7M3"] < 83


def test_jiang2013_through_colour_recovers_a_camera_from_an_undisturbed_photograph():
    truth, others = _left_out("Sony ILCE-7M3")
    rgb = (CHART * DAYLIGHT) @ truth
    # Its basis from the other 50 cameras (measured 1.3, 3.1, 1.2 % with 3 components) ...
    estimate = jiang2013_response(rgb, CHART, DAYLIGHT, WAVELENGTHS, others, components=3)
    assert peak_relative_rmse(estimate, truth).max() < 0.04
    # ... and, with the camera among 8 components' training cameras, nearly exact (0.3 %).
    estimate = jiang2013_response(rgb, CHART, DAYLIGHT, WAVELENGTHS, RESPONSES, components=8)
    assert peak_relative_rmse(estimate, truth).max() < 0.005


def test_the_prior_helps_where_a_small_chart_says_little():
    """On the 24 ColorChecker fields (few for 41 bands), undisturbed, the prior from the other
    cameras brings the estimate closer (measured 8.4 % without, 5.0 % with)."""
    truth, others = _left_out("Nikon D850")
    chart = COLORCHECKER
    rgb = (chart * DAYLIGHT) @ truth
    positions = np.array([[j % 6, j // 6] for j in range(24)], dtype=float)
    errors = [
        peak_relative_rmse(
            estimate_response(
                rgb, chart, DAYLIGHT, WAVELENGTHS, field_positions=positions, prior=prior
            ),
            truth,
        ).max()
        for prior in (None, learn_response_prior(others, WAVELENGTHS))
    ]
    assert errors[1] < 0.7 * errors[0] and errors[1] < 0.06


def test_the_prior_of_all_51_cameras_is_the_default():
    """``estimate_response`` takes the prior learned from every shipped camera unless told
    otherwise; ``prior=None`` is the thesis's method and the basic method ignores the default."""
    prior = measured_response_prior(WAVELENGTHS)
    learned = learn_response_prior(RESPONSES, WAVELENGTHS)
    np.testing.assert_allclose(prior.precision, learned.precision, rtol=1e-9)
    assert prior.cameras == 51 and measured_response_prior(WAVELENGTHS) is prior  # learned once
    truth = RESPONSES[NAMES.index("Nikon D850")]
    rgb = (COLORCHECKER * DAYLIGHT) @ truth
    positions = np.array([[j % 6, j // 6] for j in range(24)], dtype=float)

    def estimate(**options):
        return estimate_response(
            rgb, COLORCHECKER, DAYLIGHT, WAVELENGTHS, field_positions=positions, **options
        )

    np.testing.assert_array_equal(estimate(), estimate(prior=prior))
    assert not np.allclose(estimate(), estimate(prior=None))
    basic = estimate_response(rgb, COLORCHECKER, DAYLIGHT, WAVELENGTHS, method="basic")
    assert basic.shape == (41, 3)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: learn_response_prior(RESPONSES[:4], WAVELENGTHS), "at least components"),
        (lambda: learn_response_prior(RESPONSES[:, :-1], WAVELENGTHS), r"\(cameras, 41, 3\)"),
        (lambda: learn_response_prior(RESPONSES, WAVELENGTHS, components=0), "components"),
        (lambda: learn_response_prior(0 * RESPONSES, WAVELENGTHS), "positive peak"),
        (
            lambda: estimate_response(
                (CHART[:40] * DAYLIGHT) @ RESPONSES[0],
                CHART[:40],
                DAYLIGHT,
                WAVELENGTHS,
                method="basic",
                prior=learn_response_prior(RESPONSES, WAVELENGTHS),
            ),
            "only the extended method",
        ),
        (
            lambda: estimate_response(
                np.ones((113, 3)),
                np.full((113, 33), 0.5),
                np.ones(33),
                DEFAULT_GRID.wavelengths_nm,
                field_positions=np.zeros((113, 2)),
                prior=learn_response_prior(RESPONSES, WAVELENGTHS),
            ),
            "prior: learned on 41 wavelengths",
        ),
        (
            lambda: jiang2013_response(
                np.ones((185, 3)), CHART, DAYLIGHT, WAVELENGTHS, RESPONSES[:2], components=2
            ),
            "training_responses",
        ),
    ],
)
def test_bad_input_is_rejected_clearly(call, message):
    with pytest.raises(InputError, match=message):
        call()
