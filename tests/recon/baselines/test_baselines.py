"""Competing spectral recovery methods (recon.baselines), each on its defining property."""

import inspect

import colour
import numpy as np
import pytest
from scipy import linalg

from recon import baselines
from recon.baselines import (
    RECOVERY_METHODS,
    a_plus,
    dong,
    hardeberg,
    imai,
    jakob,
    jakob_hanika2019,
    murakami,
    recover,
    smits,
)
from recon.errors import InputError
from recon.metrics import relative_error
from recon.spectra import DEFAULT_GRID

WL = DEFAULT_GRID.wavelengths_nm  # 400-720 nm, 10 nm, K = 33
SHAPE = colour.SpectralShape(400, 720, 10)
CMFS_NAME = "CIE 1931 2 Degree Standard Observer"
RESPONSE = colour.MSDS_CMFS[CMFS_NAME][WL]  # (33, 3): rgb = spectra @ RESPONSE


def bump(centre: float, width: float) -> np.ndarray:
    return np.exp(-0.5 * ((WL - centre) / width) ** 2)


BASIS3 = np.array([bump(450, 40), bump(550, 40), bump(640, 50)])  # non-negative, 3-D
BASIS6 = np.array([bump(centre, 35) for centre in np.linspace(420, 700, 6)])


def draw6(rng: np.random.Generator, count: int) -> np.ndarray:
    """Smooth positive spectra spanning 6 dimensions (more than an RGB camera resolves)."""
    weights = rng.dirichlet(np.full(6, 0.3), count) * rng.uniform(0.3, 1.0, (count, 1))
    return 0.05 + weights @ BASIS6


def max_relative(estimate: np.ndarray, truth: np.ndarray) -> float:
    return float(np.abs(estimate - truth).max() / np.abs(truth).max())


# ------------------------------------------------------------------------- Imai & Berns 1999


def test_imai_is_the_minimal_norm_solution(rng):
    spectra = draw6(rng, 60).reshape(6, 10, 33)
    rgb = spectra @ RESPONSE
    estimate = imai(rgb, RESPONSE)
    assert estimate.shape == (6, 10, 33)
    # Reproduces the RGB exactly (measured 1e-15 relative) ...
    assert max_relative(estimate @ RESPONSE, rgb) < 1e-12
    # ... and has no metameric-black component (measured 1e-16 relative).
    black = linalg.null_space(RESPONSE.T)  # (33, 30): spectra s with s @ RESPONSE = 0
    assert np.abs(estimate @ black).max() < 1e-12 * np.abs(estimate).max()
    lstsq = np.linalg.lstsq(RESPONSE.T, rgb.reshape(-1, 3).T, rcond=None)[0].T
    np.testing.assert_allclose(estimate.reshape(-1, 33), lstsq, rtol=0, atol=1e-12)
    # Minimal norm, not the truth: these spectra span 6 dimensions.
    assert relative_error(estimate, spectra).mean() == pytest.approx(51.6, rel=0.15)  # measured


# ------------------------------------------------------------------ Hardeberg et al. 1999


def test_hardeberg_is_exact_in_a_three_dimensional_subspace_and_beats_imai(rng):
    spectra = (rng.uniform(0, 1, (10 * 12, 3)) @ BASIS3).reshape(10, 12, 33)
    rgb = spectra @ RESPONSE
    known = rng.choice(120, 20, replace=False)
    estimate = hardeberg(rgb, known_spectra=spectra.reshape(-1, 33)[known], known_pixels=known)
    assert max_relative(estimate, spectra) < 1e-8  # measured 1.5e-15
    imai_error = relative_error(imai(rgb, RESPONSE), spectra).mean()
    assert relative_error(estimate, spectra).mean() < 1e-6
    # Measured 44.6 %: the minimal-norm inverse ignores the scene.
    assert imai_error == pytest.approx(44.6, rel=0.15)


def test_hardeberg_reads_known_rgb_from_the_image_at_flat_indices(rng):
    spectra = draw6(rng, 48).reshape(6, 8, 33)
    rgb = spectra @ RESPONSE
    rows, cols = np.array([0, 2, 5, 5]), np.array([1, 7, 0, 3])
    known = np.ravel_multi_index((rows, cols), (6, 8))
    from_pixels = hardeberg(rgb, known_spectra=spectra[rows, cols], known_pixels=known)
    from_rgb = hardeberg(rgb, known_spectra=spectra[rows, cols], known_rgb=rgb[rows, cols])
    np.testing.assert_allclose(from_pixels, from_rgb, rtol=0, atol=1e-14)


# --------------------------------------------------------------------- Dong et al. 2016


def test_dong_is_exact_for_non_negative_mixtures_of_three_spectra(rng):
    known = rng.uniform(0, 1, (250, 3)) @ BASIS3
    spectra = (rng.uniform(0, 1, (20 * 20, 3)) @ BASIS3).reshape(20, 20, 33)
    rgb = spectra @ RESPONSE
    estimate = dong(rgb, RESPONSE, known_spectra=known)
    # NMF converges approximately: measured 2e-5 relative (tol=1e-6).
    assert max_relative(estimate, spectra) < 0.005
    # Three coefficients solve the 3x3 system exactly: RGB reproduced (measured 1e-15).
    assert max_relative(estimate @ RESPONSE, rgb) < 1e-10


def test_dong_is_limited_to_three_dimensions(rng):
    known = draw6(rng, 250)
    spectra = draw6(rng, 200)
    error = relative_error(dong(spectra @ RESPONSE, RESPONSE, known_spectra=known), spectra).mean()
    # Measured 47.9 %: six-dimensional spectra, three-dimensional basis.
    assert error == pytest.approx(47.9, rel=0.15)


# ----------------------------------------------------------------- Murakami et al. 2007


def four_material_scene():
    """24 x 24 image, four materials in quadrants (four independent spectra), smooth shading;
    16 known spectra on a regular grid (4 per material)."""
    materials = np.array(
        [
            0.1 + 0.8 * bump(450, 30),
            0.1 + 0.8 * bump(530, 30),
            0.1 + 0.8 * bump(610, 30),
            0.1 + 0.6 * bump(680, 25) + 0.4 * bump(420, 20),
        ]
    )
    labels = np.zeros((24, 24), dtype=int)
    labels[:12, 12:], labels[12:, :12], labels[12:, 12:] = 1, 2, 3
    rows, cols = np.mgrid[:24, :24]
    shading = 0.7 + 0.3 * np.cos(cols / 7.0) * np.sin(rows / 9.0)
    spectra = materials[labels] * shading[..., None]
    grid_rows, grid_cols = np.meshgrid(np.arange(3, 24, 6), np.arange(3, 24, 6), indexing="ij")
    known = np.ravel_multi_index((grid_rows.ravel(), grid_cols.ravel()), (24, 24))
    return spectra, known


def test_murakami_corrects_hardeberg_where_the_scene_has_four_materials():
    spectra, known = four_material_scene()
    rgb = spectra @ RESPONSE
    known_spectra = spectra.reshape(-1, 33)[known]
    estimate = murakami(rgb, RESPONSE, known_spectra=known_spectra, known_pixels=known)
    assert estimate.shape == (24, 24, 33)
    # Known spectra reproduced at their pixels and RGB matched (both measured ~1e-15).
    assert max_relative(estimate.reshape(-1, 33)[known], known_spectra) < 1e-10
    assert max_relative(estimate @ RESPONSE, rgb) < 1e-10
    hardeberg_error = relative_error(
        hardeberg(rgb, known_spectra=known_spectra, known_pixels=known), spectra
    ).mean()
    murakami_error = relative_error(estimate, spectra).mean()
    assert hardeberg_error == pytest.approx(20.2, rel=0.15)  # four spectra, three dimensions
    assert murakami_error == pytest.approx(9.1, rel=0.15)  # measured 9.11 %


def test_murakami_reproduces_every_pixel_when_every_spectrum_is_known():
    spectra, _ = four_material_scene()
    estimate = murakami(
        spectra @ RESPONSE,
        RESPONSE,
        known_spectra=spectra.reshape(-1, 33),
        known_pixels=np.arange(576),
    )
    assert max_relative(estimate, spectra) < 1e-10  # measured ~1e-15


def test_murakami_correction_fades_far_from_the_known_points():
    spectra, known = four_material_scene()
    rgb = spectra @ RESPONSE
    known_spectra = spectra.reshape(-1, 33)[known]
    # A huge nugget switches the correction off: the global (Wiener) estimate alone.
    wiener = murakami(rgb, RESPONSE, known_spectra=known_spectra, known_pixels=known, nugget=1e12)
    # With L = 0.05 px the correction one pixel away from a known point is exp(-20) of it.
    local = murakami(
        rgb, RESPONSE, known_spectra=known_spectra, known_pixels=known, correlation_length=0.05
    )
    elsewhere = np.setdiff1d(np.arange(576), known)
    assert max_relative(local.reshape(-1, 33)[known], known_spectra) < 1e-10
    assert max_relative(local.reshape(-1, 33)[elsewhere], wiener.reshape(-1, 33)[elsewhere]) < 1e-7
    # The global estimate alone is limited like Hardeberg's (measured 13.5 %, Hardeberg 20 %).
    assert relative_error(wiener, spectra).mean() == pytest.approx(13.5, rel=0.15)


def test_murakami_at_some_pixels_gives_those_rows_of_the_whole_image():
    """``at_pixels`` (spots held out of a cross-validation) are the same rows as the whole
    image's; ``grid_step`` interpolates the correction between a coarser grid of pixels: on
    this 24 px scene (correlation length 2.4 px) within a few percent of the values at
    steps 2 and 3, exact at the grid's own pixels and at step 1."""
    spectra, known = four_material_scene()
    rgb = spectra @ RESPONSE
    data = {"known_spectra": spectra.reshape(-1, 33)[known], "known_pixels": known}
    whole = murakami(rgb, RESPONSE, **data)
    targets = np.array([0, 5, 300, 575, 5])
    rows = murakami(rgb, RESPONSE, **data, at_pixels=targets)
    np.testing.assert_array_equal(rows, whole.reshape(-1, 33)[targets])
    np.testing.assert_array_equal(murakami(rgb, RESPONSE, **data, grid_step=1), whole)
    for step in (2, 3):
        coarse = murakami(rgb, RESPONSE, **data, grid_step=step)
        on_grid = np.ix_(np.r_[0:24:step, 23], np.r_[0:24:step, 23])
        np.testing.assert_allclose(coarse[on_grid], whole[on_grid], rtol=1e-12)
        assert 0 < max_relative(coarse, whole) < 0.15  # measured 0.049 and 0.013
    with pytest.raises(InputError, match=r"at_pixels: expected flat indices in \[0, 576\)"):
        murakami(rgb, RESPONSE, **data, at_pixels=[576])
    with pytest.raises(InputError, match="grid_step: expected a whole number of pixels >= 1"):
        murakami(rgb, RESPONSE, **data, grid_step=0)


# ------------------------------------------------------- Spectral A+ (Aeschbacher 2017)


def test_a_plus_defaults_are_sparsity_8_and_lambda_0_1(rng):
    parameters = inspect.signature(a_plus).parameters
    assert parameters["sparsity"].default == 8
    assert parameters["ridge_lambda"].default == 0.1
    train = draw6(rng, 250)
    test = draw6(rng, 100) @ RESPONSE
    default = a_plus(test, RESPONSE, known_spectra=train, known_rgb=train @ RESPONSE)
    explicit = a_plus(
        test,
        RESPONSE,
        known_spectra=train,
        known_rgb=train @ RESPONSE,
        sparsity=8,
        ridge_lambda=0.1,
    )
    np.testing.assert_array_equal(default, explicit)
    # Both parameters act (measured max differences 0.05 and 0.11).
    other_sparsity = a_plus(
        test, RESPONSE, known_spectra=train, known_rgb=train @ RESPONSE, sparsity=1
    )
    other_lambda = a_plus(
        test, RESPONSE, known_spectra=train, known_rgb=train @ RESPONSE, ridge_lambda=1e-5
    )
    assert np.abs(default - other_sparsity).max() > 1e-3
    assert np.abs(default - other_lambda).max() > 1e-3


def test_a_plus_is_exact_on_training_data_linear_in_rgb(rng):
    train = rng.uniform(0, 1, (250, 3)) @ BASIS3  # every neighbourhood: spectra linear in RGB
    rgb = train @ RESPONSE
    exact = a_plus(rgb, known_spectra=train, known_rgb=rgb, ridge_lambda=1e-10)
    assert max_relative(exact, train) < 1e-8  # measured 2e-10
    # The default ridge (lambda = 0.1 on unit-norm RGB) biases it (measured 13 % max).
    assert max_relative(a_plus(rgb, known_spectra=train, known_rgb=rgb), train) > 1e-3


def test_a_plus_beats_imai_on_held_out_spectra(rng):
    train, test = draw6(rng, 250), draw6(rng, 400)
    estimate = a_plus(test @ RESPONSE, RESPONSE, known_spectra=train, known_rgb=train @ RESPONSE)
    a_plus_error = relative_error(estimate, test).mean()
    imai_error = relative_error(imai(test @ RESPONSE, RESPONSE), test).mean()
    # Measured 36.1 % vs 51.9 % (Hardeberg: 34 %).
    assert a_plus_error == pytest.approx(36.1, rel=0.15)
    assert imai_error == pytest.approx(51.9, rel=0.15)


def test_a_plus_takes_known_rgb_from_known_pixels(rng):
    spectra = draw6(rng, 16 * 16).reshape(16, 16, 33)
    rgb = spectra @ RESPONSE
    known = rng.choice(256, 100, replace=False)
    known_spectra = spectra.reshape(-1, 33)[known]
    from_pixels = a_plus(rgb, known_spectra=known_spectra, known_pixels=known, n_atoms=32)
    from_rgb = a_plus(
        rgb, known_spectra=known_spectra, known_rgb=rgb.reshape(-1, 3)[known], n_atoms=32
    )
    np.testing.assert_array_equal(from_pixels, from_rgb)
    assert from_pixels.shape == (16, 16, 33)


# ------------------------------------------------------------------------ Smits 1999


# Smits (1999), Table 1: the seven basis spectra on ten bins evenly spaced over 380-720 nm.
SMITS_BINS = np.linspace(380, 720, 10)
SMITS_TABLE = {
    "white": [1.0000, 1.0000, 0.9999, 0.9993, 0.9992, 0.9998, 1.0000, 1.0000, 1.0000, 1.0000],
    "cyan": [0.9710, 0.9426, 1.0007, 1.0007, 1.0007, 1.0007, 0.1564, 0.0000, 0.0000, 0.0000],
    "magenta": [1.0000, 1.0000, 0.9685, 0.2229, 0.0000, 0.0458, 0.8369, 1.0000, 1.0000, 0.9959],
    "yellow": [0.0001, 0.0000, 0.1088, 0.6651, 1.0000, 1.0000, 0.9996, 0.9586, 0.9685, 0.9840],
    "red": [0.1012, 0.0515, 0.0000, 0.0000, 0.0000, 0.0000, 0.8325, 1.0149, 1.0149, 1.0149],
    "green": [0.0000, 0.0000, 0.0273, 0.7937, 1.0000, 0.9418, 0.1719, 0.0000, 0.0000, 0.0025],
    "blue": [1.0000, 1.0000, 0.8916, 0.3323, 0.0000, 0.0000, 0.0003, 0.0369, 0.0483, 0.0496],
}


def smits_by_hand(rgb: np.ndarray) -> np.ndarray:
    """Smits' algorithm written out from the paper, on its ten bins."""
    table = {name: np.array(values) for name, values in SMITS_TABLE.items()}
    primaries = ("red", "green", "blue")
    secondaries = ("cyan", "magenta", "yellow")  # the complement of red, green, blue
    result = []
    for value in rgb:
        low, middle, top = np.argsort(value, kind="stable")
        spectrum = value[low] * table["white"]
        # The two largest channels share a secondary, the complement of the smallest one.
        spectrum = spectrum + (value[middle] - value[low]) * table[secondaries[low]]
        spectrum = spectrum + (value[top] - value[middle]) * table[primaries[top]]
        result.append(spectrum)
    return np.array(result)


def test_smits_reproduces_the_published_basis_spectra_and_their_combinations(rng):
    corners = {
        "white": [1, 1, 1],
        "cyan": [0, 1, 1],
        "magenta": [1, 0, 1],
        "yellow": [1, 1, 0],
        "red": [1, 0, 0],
        "green": [0, 1, 0],
        "blue": [0, 0, 1],
    }
    for name, value in corners.items():
        np.testing.assert_allclose(
            smits(np.array([value], dtype=float), wavelengths_nm=SMITS_BINS)[0],
            SMITS_TABLE[name],
            atol=5e-5,  # the table's four decimals
            err_msg=name,
        )
    rgb = rng.uniform(0, 1, (200, 3))
    by_hand = smits_by_hand(rgb)
    np.testing.assert_allclose(smits(rgb, wavelengths_nm=SMITS_BINS), by_hand, atol=5e-5)
    # Between the bins the spectra are interpolated linearly.
    on_grid = np.array([np.interp(WL, SMITS_BINS, spectrum) for spectrum in by_hand])
    np.testing.assert_allclose(smits(rgb, wavelengths_nm=WL), on_grid, atol=5e-5)
    # In-gamut colours give physical reflectances: the table's largest value is 1.0149.
    on_wl = smits(rgb, wavelengths_nm=WL)
    assert on_wl.min() >= 0 and on_wl.max() <= 1.0149 + 5e-5


def test_smits_grey_is_flat():
    grey = smits(np.array([[0.5, 0.5, 0.5], [1.0, 1.0, 1.0]]), wavelengths_nm=WL)
    # Smits' white basis dips to 0.9992 around 500 nm: measured ptp 4e-4 and 8e-4.
    assert np.ptp(grey, axis=1).max() < 1e-3
    np.testing.assert_allclose(grey.mean(axis=1), [0.5, 1.0], atol=1e-3)


def test_smits_colour_round_trip_is_within_its_known_accuracy(rng):
    rgb = rng.uniform(0, 1, (200, 3))
    spectra = smits(rgb, wavelengths_nm=WL)
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(SHAPE)
    illuminant = colour.SDS_ILLUMINANTS["E"].copy().align(SHAPE)  # Smits' white point is E
    xyz = np.array(
        [
            colour.sd_to_XYZ(
                colour.SpectralDistribution(s, WL), cmfs, illuminant, method="Integration"
            )
            for s in spectra
        ]
    )
    back = colour.XYZ_to_RGB(xyz / 100, colour.recovery.smits1999.RGB_COLOURSPACE_SMITS1999)
    error = np.abs(back - rgb)
    # Smits' spectra are a heuristic fitted on ten coarse bins, not a colour-exact inverse
    # (colour's own docstring example is off by 0.017 in X). Measured on 200 random colours:
    # mean 0.020, max 0.087 absolute per channel.
    assert error.mean() < 0.05
    assert error.max() < 0.1


# ----------------------------------------------------------------- Jakob & Hanika 2019


def jakob_check_rgb(spectra: np.ndarray) -> np.ndarray:
    """sRGB of reflectances under D65 on the 33-band grid, via colour (see jakob)."""
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(SHAPE)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE)

    def xyz(values):
        sd = colour.SpectralDistribution(values, WL)
        return colour.sd_to_XYZ(sd, cmfs, d65, method="Integration") / 100

    white = colour.XYZ_to_xy(xyz(np.ones(33)))
    srgb = colour.models.RGB_COLOURSPACE_sRGB.copy()
    srgb.use_derived_transformation_matrices(True)
    return colour.XYZ_to_RGB(np.array([xyz(s) for s in spectra]), srgb, white)


def test_jakob_grey_is_flat_and_colours_round_trip(rng):
    grey = jakob(np.array([[0.5, 0.5, 0.5], [0.2, 0.2, 0.2]]), wavelengths_nm=WL)
    assert np.ptp(grey, axis=1).max() < 1e-9  # measured 3e-16
    np.testing.assert_allclose(grey[:, 0], [0.5, 0.2], atol=1e-9)
    rgb = np.concatenate([rng.uniform(0, 1, (100, 3)), np.eye(3) * 0.8])
    spectra = jakob(rgb.reshape(1, -1, 3), wavelengths_nm=WL)[0]
    assert spectra.min() > 0 and spectra.max() < 1
    # The coefficients are fitted to the colour: measured max error 1.4e-15.
    assert np.abs(jakob_check_rgb(spectra) - rgb).max() < 1e-6


def test_jakob_agrees_with_colours_per_colour_optimizer():
    rgb = np.array([[0.7, 0.2, 0.2], [0.1, 0.4, 0.3]])
    ours = jakob(rgb, wavelengths_nm=WL)
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(SHAPE)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE)
    srgb = colour.models.RGB_COLOURSPACE_sRGB.copy()
    srgb.use_derived_transformation_matrices(True)
    white = colour.XYZ_to_xy(np.ones(33) @ (cmfs.values * d65.values[:, None]))
    for value, spectrum in zip(rgb, ours, strict=True):
        xyz = colour.RGB_to_XYZ(value, srgb, white)
        reference = colour.XYZ_to_sd(xyz, method="Jakob 2019", cmfs=cmfs, illuminant=d65)
        # colour's optimizer stops at a Delta E threshold: measured differences 7e-5, 2e-5.
        np.testing.assert_allclose(spectrum, reference.values, atol=1e-3)


def test_jakob_lut_path_evaluates_colours_coefficients(monkeypatch):
    class FakeLUT:
        def RGB_to_coefficients(self, rgb):  # noqa: N802 (colour's name)
            return np.tile([-1e-4, 0.1, -25.0], (len(rgb), 1)).squeeze()

    requested = []

    def fake_lut(size, start, end, interval):
        requested.append((size, start, end, interval))
        return FakeLUT()

    monkeypatch.setattr(jakob_hanika2019, "_jakob_lut", fake_lut)
    result = jakob(np.array([[0.3, 0.4, 0.5]]), wavelengths_nm=WL, lut_size=4)
    expected = colour.recovery.sd_Jakob2019([-1e-4, 0.1, -25.0], SHAPE).values
    np.testing.assert_allclose(result[0], expected, rtol=1e-12)
    assert requested == [(4, 400.0, 720.0, 10.0)]


# ------------------------------------------------------------------------- bad input


GOOD_RGB = np.full((4, 5, 3), 0.3)
GOOD_SPECTRA = np.full((3, 33), 0.5)
NAN_RGB = GOOD_RGB.copy()
NAN_RGB[1, 2, 0] = np.nan


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: imai(NAN_RGB, RESPONSE), r"rgb: expected finite values, found 1 NaN"),
        (lambda: imai(GOOD_RGB, RESPONSE[:, :2]), r"response: expected shape \(K, 3\)"),
        (
            lambda: hardeberg(GOOD_RGB, known_spectra=np.empty((0, 33)), known_pixels=[]),
            r"known_spectra: no known spectra",
        ),
        (
            lambda: hardeberg(GOOD_RGB, known_spectra=GOOD_SPECTRA, known_pixels=[0, 1, 20]),
            r"known_pixels: .*\[0, 20\)",
        ),
        (
            lambda: hardeberg(GOOD_RGB, known_spectra=GOOD_SPECTRA, known_pixels=[0, 1, 1]),
            r"known_pixels: .*distinct",
        ),
        (
            lambda: hardeberg(GOOD_RGB, known_spectra=GOOD_SPECTRA, known_pixels=[0, 1]),
            r"one index per known spectrum",
        ),
        (
            lambda: hardeberg(
                GOOD_RGB, known_spectra=GOOD_SPECTRA, known_pixels=np.eye(4, 5, dtype=bool)
            ),
            r"boolean mask; pass np.flatnonzero",
        ),
        (
            lambda: hardeberg(GOOD_RGB, known_spectra=GOOD_SPECTRA),
            r"known_pixels / known_rgb: expected exactly one of them",
        ),
        (
            lambda: murakami(
                GOOD_RGB, RESPONSE[:30], known_spectra=GOOD_SPECTRA, known_pixels=[0, 1, 2]
            ),
            r"response: has 30 bands but the spectra have K = 33",
        ),
        (
            lambda: murakami(
                GOOD_RGB[0], RESPONSE, known_spectra=GOOD_SPECTRA, known_pixels=[0, 1, 2]
            ),
            r"rgb: murakami needs a 2-D image of shape \(H, W, C\)",
        ),
        (
            lambda: murakami(
                GOOD_RGB, RESPONSE, known_spectra=np.full((3, 33), np.inf), known_pixels=[0, 1, 2]
            ),
            r"known_spectra: expected finite values",
        ),
        (
            lambda: murakami(
                GOOD_RGB, RESPONSE, known_spectra=GOOD_SPECTRA, known_pixels=[0, 1, 2], nugget=-1
            ),
            r"nugget: expected a finite number >= 0",
        ),
        (
            lambda: dong(GOOD_RGB, RESPONSE, known_spectra=-GOOD_SPECTRA),
            r"known_spectra: NMF needs non-negative spectra",
        ),
        (
            lambda: dong(GOOD_RGB, RESPONSE, known_spectra=np.empty((0, 33))),
            r"known_spectra: no known spectra",
        ),
        (
            lambda: dong(GOOD_RGB, RESPONSE, known_spectra=GOOD_SPECTRA, n_components=0),
            r"n_components: expected an integer >= 1",
        ),
        (
            lambda: a_plus(GOOD_RGB, RESPONSE, known_spectra=GOOD_SPECTRA[:, :30]),
            r"response: has 33 bands but the spectra have K = 30",
        ),
        (
            lambda: a_plus(GOOD_RGB, known_spectra=GOOD_SPECTRA),
            r"known_rgb: expected known_rgb, known_pixels or response",
        ),
        (
            lambda: a_plus(GOOD_RGB, RESPONSE, known_spectra=GOOD_SPECTRA),
            r"n_atoms: expected an integer >= 1 and <= 3",
        ),
        (
            lambda: a_plus(NAN_RGB, RESPONSE, known_spectra=GOOD_SPECTRA, n_atoms=2),
            r"rgb: expected finite values",
        ),
        (
            lambda: smits(GOOD_RGB * 4, wavelengths_nm=WL),
            r"rgb: expected linear sRGB .* in \[0, 1\]",
        ),
        (
            lambda: smits(GOOD_RGB, wavelengths_nm=WL[::-1]),
            r"wavelengths_nm: expected strictly increasing",
        ),
        (lambda: jakob(NAN_RGB, wavelengths_nm=WL), r"rgb: expected finite values"),
        (lambda: jakob(GOOD_RGB[..., :2], wavelengths_nm=WL), r"rgb: expected 3 channels"),
        (
            lambda: jakob(GOOD_RGB, wavelengths_nm=WL, lut_size=1),
            r"lut_size: expected an integer >= 2",
        ),
    ],
)
def test_bad_input_is_rejected_with_a_helpful_message(call, message):
    with pytest.raises(InputError, match=message):
        call()


# ------------------------------------------------------------------------- registry and recover


def registry_case(rng: np.random.Generator) -> dict[str, tuple[tuple, dict, object]]:
    """Per registered method: the ``(rgb, response)`` and keywords of :func:`recover`, and the
    same call written against the method's function."""
    response = rng.random((12, 3))
    spectra = 0.05 + rng.random((40, 12))
    camera = (spectra @ response).reshape(5, 8, 3)
    known = np.arange(0, 40, 3)
    data = {"known_pixels": known, "known_spectra": spectra[known]}
    srgb = rng.random((2, 3, 3))
    wl = WL[::4]
    a_plus_options = {"n_atoms": 6, "sparsity": 4}
    return {
        "imai": ((camera, response), {}, lambda: imai(camera, response)),
        "hardeberg": ((camera, None), data, lambda: hardeberg(camera, **data)),
        "murakami": (
            (camera, response),
            {**data, "nugget": 0.1},
            lambda: murakami(camera, response, **data, nugget=0.1),
        ),
        "dong": (
            (camera, response),
            {"known_spectra": spectra[known], "max_iter": 200},
            lambda: dong(camera, response, known_spectra=spectra[known], max_iter=200),
        ),
        "a_plus": (
            (camera, None),
            {**data, **a_plus_options},
            lambda: a_plus(camera, **data, **a_plus_options),
        ),
        "smits": ((srgb, None), {"wavelengths_nm": wl}, lambda: smits(srgb, wavelengths_nm=wl)),
        "jakob": ((srgb, None), {"wavelengths_nm": wl}, lambda: jakob(srgb, wavelengths_nm=wl)),
    }


def test_recover_by_name_equals_calling_the_method(rng):
    cases = registry_case(rng)
    assert set(cases) == set(RECOVERY_METHODS)  # a new method needs a case here
    for name, (args, keywords, direct) in cases.items():
        expected = direct()
        assert np.array_equal(recover(*args, method=name, **keywords), expected), name
        assert np.array_equal(recover(*args, method=name.upper(), **keywords), expected), name


@pytest.mark.parametrize("method", ["wiener", "", "imai 1999", "aplus", None])
def test_recover_rejects_an_unknown_method_naming_the_valid_ones(method):
    with pytest.raises(InputError, match=r"^method: unknown spectral recovery method") as info:
        recover(GOOD_RGB, RESPONSE, method=method)
    message = str(info.value)
    assert repr(method) in message and "\n" not in message
    for name in RECOVERY_METHODS:
        assert name in message


@pytest.mark.parametrize(
    ("method", "keywords", "message"),
    [
        (
            "dong",
            {"known_spectra": GOOD_SPECTRA, "n_component": 2},
            "options: method 'dong' has no option n_component; its options are n_components, "
            "random_state, max_iter, tol",
        ),
        (
            "a_plus",
            {"known_spectra": GOOD_SPECTRA, "lambda_": 1.0, "atoms": 2},
            "options: method 'a_plus' has no option atoms, lambda_; its options are known_rgb, "
            "n_atoms, sparsity, ridge_lambda, neighbourhood_size, n_iter, random_state",
        ),
        (
            "imai",
            {"rcond": 1e-6},
            "options: method 'imai' has no option rcond; its options are none",
        ),
    ],
)
def test_recover_rejects_an_unknown_option_naming_the_valid_ones(method, keywords, message):
    with pytest.raises(InputError) as info:
        recover(GOOD_RGB, RESPONSE, method=method, **keywords)
    assert str(info.value) == message


@pytest.mark.parametrize(
    ("method", "response", "message"),
    [
        ("hardeberg", None, "known_spectra: method 'hardeberg' needs known_spectra"),
        (
            "murakami",
            RESPONSE,
            "known_spectra: method 'murakami' needs known_spectra and known_pixels",
        ),
        ("dong", RESPONSE, "known_spectra: method 'dong' needs known_spectra"),
        ("a_plus", RESPONSE, "known_spectra: method 'a_plus' needs known_spectra"),
        ("smits", None, "wavelengths_nm: method 'smits' needs wavelengths_nm"),
    ],
)
def test_recover_names_what_a_method_needs_and_did_not_get(method, response, message):
    with pytest.raises(InputError) as info:
        recover(GOOD_RGB, response, method=method)
    assert str(info.value) == message


@pytest.mark.parametrize(
    ("method", "response", "keywords", "message"),
    [
        ("imai", None, {}, r"^response: method 'imai' needs the \(K, C\) response"),
        ("smits", RESPONSE, {"wavelengths_nm": WL}, r"^response: method 'smits' uses no response"),
        (
            "imai",
            RESPONSE,
            {"known_spectra": GOOD_SPECTRA},
            r"^known_spectra: method 'imai' does not use known_spectra; pass None$",
        ),
        (
            "dong",
            RESPONSE,
            {"known_spectra": GOOD_SPECTRA, "known_pixels": [0, 1, 2]},
            r"^known_pixels: method 'dong' does not use known_pixels; pass None$",
        ),
    ],
)
def test_recover_rejects_data_a_method_does_not_use(method, response, keywords, message):
    with pytest.raises(InputError, match=message):
        recover(GOOD_RGB, response, method=method, **keywords)


def test_one_name_and_one_signature_shape_per_method():
    assert list(RECOVERY_METHODS) == [
        "imai",
        "hardeberg",
        "murakami",
        "dong",
        "a_plus",
        "smits",
        "jakob",
    ]
    assert sorted(baselines.__all__) == sorted([*RECOVERY_METHODS, "RECOVERY_METHODS", "recover"])
    for name, function in RECOVERY_METHODS.items():
        assert getattr(baselines, name) is function and function.__name__ == name, name
        # rgb, then the response if the method uses one, everything else by keyword.
        parameters = list(inspect.signature(function).parameters.values())
        leading = [p.name for p in parameters if p.kind is not p.KEYWORD_ONLY]
        assert leading in (["rgb"], ["rgb", "response"]), name
