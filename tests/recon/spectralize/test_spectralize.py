"""Spectralization (thesis chapters 6 and 10): energies, weights, neighbour graph and solvers."""

from __future__ import annotations

import colour
import numpy as np
import pytest
from scipy import linalg as dense_linalg
from scipy import sparse
from scipy.sparse import linalg
from scipy.spatial import cKDTree

from recon.errors import InputError
from recon.experiments.synthetic_images import material_mosaic
from recon.metrics import relative_error
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid
from recon.spectralize.appearance import (
    appearance_neighbours,
    appearance_points,
    connect_components,
)
from recon.spectralize.kronecker import solve_kronecker_sum
from recon.spectralize.solve import (
    BandImage,
    DeviceIntegrals,
    EnergyWeights,
    PointSpectra,
    build_problem,
    reconstruct,
    spectralize,
)

WAVELENGTHS = DEFAULT_GRID.wavelengths_nm
SIX = ["dark skin", "blue sky", "orange", "purplish blue", "yellow green", "cyan"]


def _chart(names):
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    return np.array([[chart[name][w] for w in WAVELENGTHS] for name in names])


def _response():
    camera = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    response = np.array([camera[w] for w in WAVELENGTHS])
    return response / response.sum(axis=0)


@pytest.fixture(scope="module")
def mosaic():
    image, labels = material_mosaic(_chart(SIX), (40, 48), cells=24, seed=3)
    return image, labels, _response()


def _grid_pixels(shape, step):
    rows, cols = np.mgrid[step // 2 : shape[0] : step, step // 2 : shape[1] : step]
    return (rows * shape[1] + cols).ravel()


def test_every_spectrum_known_and_no_noise_is_exact(mosaic):
    # Six flat materials: the truth zeroes every term of Eq. 6.10, so it is the unique minimum.
    image, _ = material_mosaic(_chart(SIX), (40, 48), cells=24, shading=(1.0, 1.0), seed=3)
    response = mosaic[2]
    flat = image.reshape(-1, image.shape[-1])
    known = PointSpectra(np.arange(flat.shape[0]), flat)
    result = reconstruct(image @ response, response, point_spectra=known, tol=1e-10)
    assert result.solver == "multigrid" and result.converged
    assert relative_error(result.spectra, image).mean() < 0.1
    # With shading, neighbours differ and the prior pulls (0.13 % at equal weights); a
    # heavier data term (alpha' = 10) brings the known spectra back below 0.1 %.
    shaded = mosaic[0]
    flat = shaded.reshape(-1, shaded.shape[-1])
    known = PointSpectra(np.arange(flat.shape[0]), flat)
    equal = reconstruct(shaded @ response, response, point_spectra=known, tol=1e-10)
    heavy = reconstruct(
        shaded @ response,
        response,
        point_spectra=known,
        weights=EnergyWeights(alpha=10.0),
        tol=1e-10,
    )
    assert relative_error(heavy.spectra, shaded).mean() < 0.1
    assert (
        relative_error(heavy.spectra, shaded).mean() < relative_error(equal.spectra, shaded).mean()
    )


def test_solvers_reach_the_same_minimum_and_multigrid_beats_500_lsqr_iterations(mosaic):
    image, _, response = mosaic
    rgb = image @ response
    rgb = rgb + 0.01 * rgb.mean() * np.random.default_rng(0).standard_normal(rgb.shape)
    pixels = _grid_pixels(image.shape[:2], 8)
    known = PointSpectra(pixels, image.reshape(-1, image.shape[-1])[pixels])
    common = {"point_spectra": known}
    multigrid = reconstruct(rgb, response, solver="multigrid", tol=1e-10, **common)
    lsqr = reconstruct(rgb, response, solver="lsqr", tol=1e-14, max_iterations=500, **common)
    lsmr = reconstruct(rgb, response, solver="lsmr", tol=1e-14, max_iterations=3000, **common)
    assert multigrid.energy <= lsqr.energy * (1 + 1e-9)
    assert lsmr.energy == pytest.approx(multigrid.energy, rel=1e-6)
    assert np.max(np.abs(lsmr.spectra - multigrid.spectra)) < 1e-3 * image.max()


def test_default_multigrid_energy_is_within_1e_4_of_a_direct_solve():
    """The default stopping rule against scipy's sparse direct solver on every decoupled band
    column (Eq. 6.10 with RGBXY neighbours; 1 % noise on the known spectra makes all 30
    metameric-black columns independent, so the whole block of them is exercised)."""
    image, _ = material_mosaic(_chart(SIX), (96, 96), cells=40, seed=5)
    response = _response()
    rng = np.random.default_rng(7)
    rgb = image @ response
    rgb = rgb + 0.01 * rgb.mean() * rng.standard_normal(rgb.shape)
    pixels = _grid_pixels(image.shape[:2], 6)
    spectra = image.reshape(-1, image.shape[-1])[pixels]
    spectra = spectra + 0.01 * spectra.mean() * rng.standard_normal(spectra.shape)
    energy = {"point_spectra": PointSpectra(pixels, spectra), "appearance": "rgbxy"}
    problem = build_problem(rgb, response, **energy)
    spatial, spectral, rhs = problem.kronecker_parts()
    dense = rhs.left @ rhs.right + rhs.rows.toarray()  # C, kept in factors by the solver
    assert np.allclose(rhs.gram(), dense.T @ dense, rtol=1e-12, atol=0)
    shifts, basis = np.linalg.eigh(spectral)
    rotated = rhs @ basis
    assert np.allclose(rotated, dense @ basis, rtol=1e-12, atol=1e-12 * np.abs(dense).max())
    identity = sparse.identity(spatial.shape[0])
    columns = [
        linalg.spsolve((spatial + shift * identity).tocsc(), column)
        for shift, column in zip(shifts, rotated.T, strict=True)
    ]
    direct = np.column_stack(columns) @ basis.T
    converged = problem.energy(direct)
    default = reconstruct(rgb, response, **energy)
    assert default.solver == "multigrid" and default.converged
    assert converged <= default.energy <= converged * (1 + 1e-4)
    # The reported energy (prior term from the solver's compressed coefficients) is the energy
    # of the returned spectra.
    spectra = default.spectra.reshape(direct.shape)
    assert default.energy == pytest.approx(problem.energy(spectra), rel=1e-12)
    assert problem.terms[2].sum_of_squares(spectra) == pytest.approx(
        np.sum((problem.terms[2].incidence @ spectra) ** 2), rel=1e-12
    )
    assert np.max(np.abs(default.spectra.reshape(direct.shape) - direct)) < 1e-3 * image.max()
    # The column parts iterate in threads, yet every run gives the same bits.
    assert np.array_equal(reconstruct(rgb, response, **energy).spectra, default.spectra)


def test_kronecker_solver_matches_scipys_sylvester_solver():
    """A X + X B = C against scipy's dense Bartels-Stewart solver, with a graph Laplacian plus
    data weights for A and a B with a repeated zero eigenvalue (shared-matrix columns that are
    compressed and iterated in interleaved parts), a small and a large shift (multigrid and
    Jacobi preconditioning)."""
    rng = np.random.default_rng(3)
    n, bands = 900, 7
    links = sparse.random(n, n, density=6 / n, random_state=4)
    adjacency = ((links + links.T) > 0).astype(float)
    laplacian = sparse.diags(np.ravel(adjacency.sum(axis=1))) - adjacency
    spatial = (laplacian + sparse.diags((rng.random(n) < 0.05).astype(float) + 1e-3)).tocsr()
    basis, _ = np.linalg.qr(rng.standard_normal((bands, bands)))
    spectral = basis @ np.diag([0, 0, 0, 0, 0.02, 0.5, 30.0]) @ basis.T
    rhs = rng.standard_normal((n, bands))
    solved, info = solve_kronecker_sum(spatial, spectral, rhs, rtol=1e-10)
    expected = dense_linalg.solve_sylvester(spatial.toarray(), spectral, rhs)
    assert info.converged and info.hierarchies >= 1
    assert np.max(np.abs(solved - expected)) < 1e-6 * np.max(np.abs(expected))


def test_energy_and_weights_follow_eq_6_10_and_6_11(mosaic):
    image, _, response = mosaic
    rgb = image @ response
    pixels = _grid_pixels(image.shape[:2], 10)
    flat = image.reshape(-1, image.shape[-1])
    problem = build_problem(
        rgb, response, point_spectra=PointSpectra(pixels, flat[pixels]), appearance="rgb"
    )
    n, bands, m = flat.shape[0], flat.shape[1], pixels.size
    links = problem.graph_links
    total = m * bands + 3 * n + bands * links
    alpha, beta, gamma = problem.weights
    assert alpha == pytest.approx(total / (m * bands))
    assert beta == pytest.approx(flat[pixels].mean() / rgb.mean() * total / (3 * n))
    assert gamma == pytest.approx(total / (bands * links))
    # E at a random image equals the sum of the three terms of Eq. 6.10 written out.
    x = np.random.default_rng(1).random(flat.shape)
    incidence = problem.terms[2].incidence
    by_hand = (
        alpha * np.sum((x[pixels] - flat[pixels]) ** 2)
        + beta * np.sum((x @ response - rgb.reshape(-1, 3)) ** 2)
        + gamma * np.sum((incidence @ x) ** 2)
    )
    assert problem.energy(x) == pytest.approx(by_hand, rel=1e-12)
    assert abs(incidence).sum(axis=1).max() == 2  # every row is one S_i - S_j


def test_operator_adjoint_holds_for_every_term(mosaic):
    image, _, response = mosaic
    shape = image.shape[:2]
    flat = image.reshape(-1, image.shape[-1])
    rng = np.random.default_rng(2)
    pixels = _grid_pixels(shape, 9)
    device = sparse.random(5, flat.size, density=0.01, random_state=3, format="csr")
    problem = build_problem(
        image @ response,
        response,
        point_spectra=PointSpectra(pixels, flat[pixels]),
        band_images=[
            BandImage(0, 4, image[..., 4], 1.5, rng.random(shape)),
            BandImage(0, 20, image[..., 20], 0.0),
        ],
        device_integrals=DeviceIntegrals(device, device @ flat.ravel()),
        p_dyn=0.5,
    )
    operator, _ = problem.operator()
    x, y = rng.standard_normal(operator.shape[1]), rng.standard_normal(operator.shape[0])
    assert np.dot(operator.matvec(x), y) == pytest.approx(np.dot(x, operator.rmatvec(y)), rel=1e-10)
    assert len(problem.weights) == 7  # point, 2 band images, device, camera, prior, smoothness


@pytest.mark.parametrize("sigma_px", [0.0, 1.5])
def test_a_band_texel_of_weight_zero_gives_no_data(mosaic, sigma_px):
    """A band image's texels weighed 0 leave the solution as it is whatever their values (a
    dark line's band values misregistered onto bright neighbours), matched pixel by pixel or
    after a Gaussian filter (the weight comes before it), while weighed 1 they pull it."""
    image, _, response = mosaic
    shape = image.shape[:2]
    weight = np.ones(shape)
    weight[20, 10:30] = 0.0
    spoiled = image[..., 12].copy()
    spoiled[20, 10:30] *= 5.0
    line = np.abs(image[20, 10:30, 12]).mean()

    def pull(weights):
        def solved(values):
            bands = [BandImage(0, band, image[..., band], sigma_px) for band in (4, 20)]
            bands.append(BandImage(0, 12, values, sigma_px, weights))
            return reconstruct(image @ response, response, band_images=bands, tol=1e-10).spectra

        return float(np.abs(solved(spoiled) - solved(image[..., 12]))[20, 10:30, 12].mean())

    assert pull(weight) < 1e-6 * line
    assert pull(None) > 0.05 * line


def test_a_band_weight_of_another_shape_or_range_is_refused(mosaic):
    image, _, response = mosaic
    for weight in (np.ones((3, 3)), np.full(image.shape[:2], 2.0)):
        band = BandImage(0, 4, image[..., 4], 0.0, weight)
        with pytest.raises(InputError, match="expected a weight of shape"):
            reconstruct(image @ response, response, band_images=[band])


@pytest.mark.parametrize("n_points", [300, 60_000])
def test_link_rule_matches_a_sequential_brute_force(n_points):
    """The rule of section 6.2 against a pixel-by-pixel loop; 60 000 points are above the size
    where each round's rows are split between two threads."""
    points = np.random.default_rng(4).random((n_points, 3))
    graph = appearance_neighbours(points, k=3, candidates=6)
    order = cKDTree(points).query(points, k=7)[1][:, 1:]
    chosen: list[list[int]] = []
    for j in range(len(points)):
        allowed = [c for c in order[j] if not (c < j and j in chosen[c])]
        chosen.append(allowed[:3])
    expected = {(j, c) for j in range(len(points)) for c in chosen[j]}
    assert set(zip(graph.first.tolist(), graph.second.tolist(), strict=True)) == expected
    pairs = {frozenset(p) for p in expected}
    assert len(pairs) == len(expected)  # no link counted twice


def test_appearance_spaces_shapes_and_patch_centre_weight():
    images = np.random.default_rng(5).random((2, 6, 7, 3))
    assert appearance_points(images, "rgb").shape == (84, 3)
    assert appearance_points(images, "rgbxy").shape == (84, 5)
    patch = appearance_points(images, "patch", patch_radius=1)
    assert patch.shape == (84, 27)
    centre = patch[:, 12:15]  # the 5th of 9 patch positions, weighted by (2m+1)^2 - 1 = 8
    assert np.allclose(centre, 8 * images.reshape(-1, 3))


def test_components_without_data_are_linked_and_determined(mosaic):
    image, labels, response = mosaic
    rgb = image @ response
    flat = image.reshape(-1, image.shape[-1])
    # Spectra known only on material 0: in RGB space the other materials float free.
    pixels = np.flatnonzero(labels.ravel() == 0)[::7]
    points = appearance_points(rgb[None], "rgb")
    graph = appearance_neighbours(points)
    has_data = np.zeros(flat.shape[0], dtype=bool)
    has_data[pixels] = True
    linked = connect_components(graph, points, has_data)
    assert linked.added >= 1 and linked.n_links == graph.n_links + linked.added
    known = PointSpectra(pixels, flat[pixels])
    first = reconstruct(rgb, response, point_spectra=known, appearance="rgb", tol=1e-10)
    warm = reconstruct(
        rgb,
        response,
        point_spectra=known,
        appearance="rgb",
        solver="lsmr",
        tol=1e-14,
        max_iterations=20000,
        initial=np.ones_like(image),
    )
    # Unique minimum: a solver started elsewhere ends at the same spectra.
    assert np.max(np.abs(warm.spectra - first.spectra)) < 1e-3


def test_joint_reconstruction_spreads_spectra_to_an_image_without_data(mosaic):
    image, _, response = mosaic
    slices = np.stack([image, 0.5 * image[:, ::-1]])  # a second, darker and mirrored view
    rgb = slices @ response
    pixels = _grid_pixels(image.shape[:2], 6)  # first image only
    known = PointSpectra(pixels, image.reshape(-1, image.shape[-1])[pixels])
    result = reconstruct(rgb, response, point_spectra=known, p_dyn=1.0, tol=1e-9)
    assert result.spectra.shape == slices.shape
    second = relative_error(result.spectra[1], slices[1]).mean()
    assert second < 5e-6, second  # measured 1.8e-6 % (3e-6 % on another machine)


def test_noisy_band_images_with_filter_beat_the_raw_band_images(mosaic):
    image, _, response = mosaic
    rng = np.random.default_rng(6)
    noisy = image + 0.1 * image.mean() * rng.standard_normal(image.shape)
    bands = [BandImage(0, b, noisy[..., b], 1.0) for b in range(image.shape[-1])]
    result = reconstruct(
        image @ response, response, band_images=bands, tol=1e-10, max_iterations=2000
    )
    assert result.solver == "lsmr"
    raw = relative_error(noisy, image).mean()
    recovered = relative_error(result.spectra, image).mean()
    assert recovered < 0.5 * raw, (recovered, raw)


def test_band_images_start_lsmr_from_their_regression_toward_the_same_minimum(mosaic):
    """Without ``initial``, LSMR starts from the band images' regression (per band, the filtered
    camera values' least-squares map to the filtered band values, applied to every pixel): the
    minimum found from zero, in fewer iterations. Two images solved jointly, the band images of
    the first only, as the dome's (measured: 252 iterations against 293 from zero)."""
    image, _, response = mosaic
    rng = np.random.default_rng(6)
    noisy = image + 0.1 * image.mean() * rng.standard_normal(image.shape)
    rgb = np.stack([image, 0.6 * image[::-1]]) @ response  # another view, dimmer
    bands = [BandImage(0, b, noisy[..., b], 1.0) for b in range(image.shape[-1])]
    options = {"band_images": bands, "tol": 1e-8, "max_iterations": 3000}
    started = reconstruct(rgb, response, **options)
    from_zero = reconstruct(rgb, response, initial=np.zeros((2, *image.shape)), **options)
    assert started.converged and from_zero.converged
    assert started.iterations < 0.9 * from_zero.iterations
    np.testing.assert_allclose(started.spectra, from_zero.spectra, atol=1e-4 * image.max())
    assert started.energy == pytest.approx(from_zero.energy, rel=1e-6)


def test_device_integrals_equal_point_spectra_for_single_pixel_readings(mosaic):
    image, _, response = mosaic
    flat = image.reshape(-1, image.shape[-1])
    pixels = _grid_pixels(image.shape[:2], 8)
    bands = flat.shape[1]
    columns = (pixels[:, None] * bands + np.arange(bands)).ravel()
    weights = sparse.csr_matrix(
        (np.ones(columns.size), (np.arange(columns.size), columns)), shape=(columns.size, flat.size)
    )
    rgb = image @ response
    via_device = reconstruct(
        rgb,
        response,
        device_integrals=DeviceIntegrals(weights, flat[pixels].ravel()),
        solver="lsmr",
        tol=1e-14,
        max_iterations=5000,
    )
    via_points = reconstruct(
        rgb, response, point_spectra=PointSpectra(pixels, flat[pixels]), tol=1e-10
    )
    assert np.max(np.abs(via_device.spectra - via_points.spectra)) < 1e-3


def test_an_area_reading_anchors_one_component_and_a_given_map_sets_the_base(mosaic):
    """A reading of the mean over every pixel fixes one value per band, not one per graph
    component: the RGB graph's components (at least one per material) are linked to the first
    pixel's as if they had no data; ``regression=`` gives the base :math:`B = f V W`."""
    image, labels, response = mosaic
    flat = image.reshape(-1, image.shape[-1])
    bands = flat.shape[1]
    mean = sparse.kron(np.full((1, flat.shape[0]), 1 / flat.shape[0]), sparse.identity(bands))
    reading = DeviceIntegrals(sparse.csr_matrix(mean), flat.mean(axis=0))
    rgb = image @ response
    points = appearance_points(rgb[None], "rgb")
    components = connect_components(
        appearance_neighbours(points), points, labels.ravel() == labels.ravel()[0]
    ).added
    regression = np.random.default_rng(5).random((3, bands))
    problem = build_problem(
        rgb,
        response,
        device_integrals=reading,
        appearance="rgb",
        prior="regression",
        regression=regression,
    )
    assert components >= len(SIX) - 1 and problem.graph_added == components
    assert np.allclose(problem.base, rgb.reshape(-1, 3) @ regression)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"rgb": np.full((4, 4, 3), np.nan)}, "rgb: camera values must be finite"),
        ({"response": np.ones((33, 2))}, "response: expected"),
        ({"point_spectra": None}, "no spectral data"),
        ({"point_spectra": PointSpectra(np.array([0]), np.ones((1, 20)))}, "expected shape"),
        ({"point_spectra": PointSpectra(np.array([99]), np.ones((1, 33)))}, "expected indices"),
        ({"point_spectra": PointSpectra(np.array([0]), np.full((1, 33), np.nan))}, "finite"),
        ({"solver": "cholesky"}, "solver: expected one of"),
        ({"p_dyn": 2.0}, "p_dyn"),
        ({"appearance": "lab"}, "unknown space"),
        ({"band_images": [BandImage(0, 3, np.ones((5, 5)), 1.0)]}, "has shape"),
        ({"band_images": [BandImage(0, 3, np.ones((4, 4)), 1.0)], "solver": "multigrid"}, "lsqr"),
        ({"prior": "regression", "regression": np.ones((3, 20))}, "regression: expected a finite"),
        ({"regression": np.ones((3, 33))}, "regression: a map for prior='regression'"),
    ],
)
def test_bad_input_is_refused_with_a_clear_message(change, message):
    arguments = {
        "rgb": np.random.default_rng(7).random((4, 4, 3)),
        "response": _response(),
        "point_spectra": PointSpectra(np.array([0, 5]), np.ones((2, 33))),
    }
    arguments.update(change)
    rgb, response = arguments.pop("rgb"), arguments.pop("response")
    with pytest.raises(InputError, match=message):
        reconstruct(rgb, response, **arguments)


def test_spectra_on_another_grid_are_refused():
    response = SampledSpectra(DEFAULT_GRID, _response().T)
    other = WavelengthGrid.regular(400, 720, 20)
    known = PointSpectra(np.array([0]), SampledSpectra(other, np.ones((1, other.size))))
    with pytest.raises(InputError, match="resample"):
        reconstruct(np.ones((3, 3, 3)), response, point_spectra=known)


def test_progress_is_reported_for_both_solver_families(mosaic, capsys):
    image, _, response = mosaic
    pixels = _grid_pixels(image.shape[:2], 8)
    known = PointSpectra(pixels, image.reshape(-1, image.shape[-1])[pixels])
    quiet = reconstruct(image @ response, response, point_spectra=known, tol=1e-8)
    shown = reconstruct(image @ response, response, point_spectra=known, tol=1e-8, progress=True)
    reconstruct(image @ response, response, point_spectra=known, solver="lsmr", progress=True)
    printed = capsys.readouterr()
    assert "spectralize: band columns" in printed.err and "spectralize: lsmr" in printed.err
    assert printed.out == ""  # standard output stays free for results
    assert np.array_equal(quiet.spectra, shown.spectra)


def test_stable_entry_point_returns_the_cube_of_the_detailed_call(mosaic):
    image, _, response = mosaic
    pixels = _grid_pixels(image.shape[:2], 8)
    flat = image.reshape(-1, image.shape[-1])
    cube = spectralize(
        image @ response, response, known_pixels=pixels, known_spectra=flat[pixels], tol=1e-9
    )
    detailed = reconstruct(
        image @ response,
        response,
        point_spectra=PointSpectra(pixels, flat[pixels]),
        appearance="rgb",
        neighbours=3,
        tol=1e-9,
    )
    assert isinstance(cube, np.ndarray) and np.array_equal(cube, detailed.spectra)
    with pytest.raises(InputError, match="give both"):
        spectralize(image @ response, response, known_pixels=pixels)
