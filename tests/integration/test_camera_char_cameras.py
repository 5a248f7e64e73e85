"""Camera characterization of measured cameras left out of the prior that guides it
(twin.studies.camchar_cameras: 240 measured fields, D65, specularity U[0, 0.1], shading in
[0.8, 1.2], noise 0.5 %, seed 0).

The goal over all 51 cameras (mean at most 4 %, largest at most 7 % of the peak) takes about a
minute here, so it is asserted on a fixed subset that holds the hardest cameras of
``benchmarks/camchar_cameras.py`` at seed 0 (BENCHMARKS.md): the four hardest for the estimate
with prior, the Canon PowerShot S90 and ARRI D21 first (hardest at seeds 0-3 as well), and the
hardest for the thesis's estimator (Canon EOS-1Ds Mark II) and for Jiang 2013 among the DSLRs
(Nikon D850). The subset's mean is above the 51 cameras' (2.59 % at seed 0), so its bound is
the stricter one.
"""

import numpy as np
import pytest

from twin.studies.camchar_cameras import BOUNDS_PCT, characterize_cameras

HARDEST = (
    "Canon PowerShot S90",  # measured at seed 0: 4.82 % with prior, 5.57 % without
    "ARRI D21",  # 4.17 %, 4.70 %
    "Nikon D5100",  # 3.51 %, 5.75 %
    "Nikon D3300",  # 3.34 %, 5.41 %
    "Canon EOS-1Ds Mark II",  # 3.18 %, 7.20 % (the thesis's hardest)
    "Nikon D850",  # 2.73 %, 6.78 %
)


@pytest.fixture(scope="module")
def hardest():
    return characterize_cameras(HARDEST, seed=0, methods=("prior", "extended"))


def test_the_prior_from_the_other_cameras_meets_the_goal_on_the_hardest_cameras(hardest):
    errors = np.array([result.errors_pct["prior"] for result in hardest])
    # Measured: mean 3.63 %, largest 4.82 % (the Canon PowerShot S90).
    assert errors.mean() <= BOUNDS_PCT["mean"]
    assert errors.max() <= BOUNDS_PCT["max"]


def test_the_prior_helps_every_one_of_them_and_most_where_the_thesis_is_worst(hardest):
    improvement = {
        result.camera: result.errors_pct["extended"] - result.errors_pct["prior"]
        for result in hardest
    }
    assert min(improvement.values()) > 0.3  # measured 0.53 points (ARRI D21) ...
    # ... to 4.05 (Nikon D850) and 4.02 (Canon EOS-1Ds Mark II), the thesis's two worst here.
    assert set(sorted(improvement, key=improvement.get)[-2:]) == {
        "Nikon D850",
        "Canon EOS-1Ds Mark II",
    }


def test_the_hardest_cameras_for_the_prior_are_the_least_like_the_others(hardest):
    """E_prior of the true response under its leave-one-out prior: the PowerShot S90 (a compact
    camera) and the ARRI D21 (a cinema camera whose red channel answers 40 % in the green)
    score 1500 and 913; the median over the 51 cameras is 83."""
    energy = {result.camera: result.prior_energy for result in hardest}
    far = min(energy["Canon PowerShot S90"], energy["ARRI D21"])
    assert far > 3 * max(e for camera, e in energy.items() if camera not in HARDEST[:2])
