"""Error measures (recon.metrics)."""

import numpy as np
import pytest

from recon.errors import InputError
from recon.metrics import peak_relative_rmse, relative_error


def test_relative_error_follows_eq_6_8():
    truth = np.array([[0.5, 0.25, 0.0]])
    estimate = np.array([[0.55, 0.25, 0.001]])
    expected = 100 / 3 * (0.05 / 0.501 + 0.0 + 0.001 / 0.001)
    assert relative_error(estimate, truth)[0] == pytest.approx(expected)


def test_peak_relative_rmse_ignores_a_global_scale_when_asked():
    truth = np.abs(np.sin(np.linspace(0, 3, 33)))[:, None] * np.array([1.0, 0.5, 0.2])
    assert peak_relative_rmse(3.0 * truth, truth).max() < 1e-12
    assert peak_relative_rmse(3.0 * truth, truth, fit_scale=False).max() > 1
    with pytest.raises(InputError, match="shape"):
        peak_relative_rmse(truth, truth[:, :2])
