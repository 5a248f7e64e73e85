"""Wavelength grids, resampling, band integrals and colour conversion (recon.spectra)."""

import colour
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from recon.errors import InputError
from recon.spectra import (
    DEFAULT_GRID,
    SampledSpectra,
    WavelengthGrid,
    band_integrals,
    from_colour,
    resample,
    to_colour,
)

FINE = WavelengthGrid.regular(380, 780, 1)


def _colorchecker_under_d65(grid: WavelengthGrid) -> SampledSpectra:
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    reflectances = from_colour(colour.MultiSpectralDistributions(list(chart.values())))
    d65 = from_colour(colour.SDS_ILLUMINANTS["D65"])
    return resample(reflectances, grid, method="pchip") * resample(d65, grid, method="pchip")


def _camera(name: str, grid: WavelengthGrid) -> SampledSpectra:
    return resample(from_colour(colour.MSDS_CAMERA_SENSITIVITIES[name]), grid, method="pchip")


def test_default_grid_is_the_lctf_grid():
    assert DEFAULT_GRID.size == 33
    assert DEFAULT_GRID.start_nm == 400 and DEFAULT_GRID.stop_nm == 720
    np.testing.assert_array_equal(np.diff(DEFAULT_GRID.wavelengths_nm), 10.0)


def test_quadrature_weights_integrate_polynomials_of_degree_one_exactly():
    grid = WavelengthGrid(np.array([400.0, 403.0, 410.0, 431.5, 450.0]))
    values = 2.0 * grid.wavelengths_nm + 7.0
    exact = (450.0**2 - 400.0**2) + 7.0 * 50.0
    assert np.sum(grid.quadrature_weights() * values) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize(
    ("wavelengths", "message"),
    [
        ([400.0, 410.0, 405.0], "strictly increasing"),
        ([400.0, 400.0, 410.0], "strictly increasing"),
        ([400.0, np.nan, 420.0], "finite"),
        ([[400.0, 410.0]], "1-D"),
        ([400.0], "at least 2"),
        ([-5.0, 10.0], "positive"),
    ],
)
def test_malformed_grids_are_rejected_with_the_reason(wavelengths, message):
    with pytest.raises(InputError, match=message):
        WavelengthGrid(np.array(wavelengths))


def test_regular_grid_needs_a_whole_number_of_steps():
    with pytest.raises(InputError, match="integer"):
        WavelengthGrid.regular(400, 720, 7)


def test_spectra_must_match_their_grid_and_be_finite():
    with pytest.raises(InputError, match="last axis"):
        SampledSpectra(DEFAULT_GRID, np.ones(32))
    with pytest.raises(InputError, match="NaN"):
        SampledSpectra(DEFAULT_GRID, np.full(33, np.nan))
    with pytest.raises(InputError, match="one name per row"):
        SampledSpectra(DEFAULT_GRID, np.ones((2, 33)), ("a",))


def test_negative_spectra_are_rejected_where_not_allowed():
    values = np.ones(33)
    values[5] = -0.1
    with pytest.raises(InputError, match="non-negative.*450 nm"):
        SampledSpectra(DEFAULT_GRID, values).require_non_negative("lamp power")


def test_mismatched_grids_are_never_combined():
    fine = SampledSpectra(FINE, np.ones(FINE.size))
    coarse = SampledSpectra(DEFAULT_GRID, np.ones((3, 33)))
    with pytest.raises(InputError, match="grids differ"):
        band_integrals(fine, coarse)
    with pytest.raises(InputError, match="grids differ"):
        fine * coarse


def test_resampling_outside_the_source_range_follows_the_policy():
    source = SampledSpectra(DEFAULT_GRID, np.linspace(1.0, 2.0, 33))
    wide = WavelengthGrid.regular(380, 740, 10)
    with pytest.raises(InputError, match="leaves the source range"):
        resample(source, wide)
    zero = resample(source, wide, out_of_range="zero").values
    clamp = resample(source, wide, out_of_range="clamp").values
    assert zero[0] == 0 and zero[-1] == 0
    assert clamp[0] == 1.0 and clamp[-1] == 2.0
    np.testing.assert_allclose(zero[2:-2], source.values)
    with pytest.raises(InputError, match="method"):
        resample(source, wide, method="nearest")


@pytest.mark.parametrize("method", ["linear", "pchip", "box"])
def test_downsampling_to_5_nm_keeps_band_integrals_within_half_a_percent(method):
    coarse = WavelengthGrid.regular(380, 780, 5)
    spectra = _colorchecker_under_d65(FINE)
    observer = resample(
        from_colour(colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]), FINE, method="pchip"
    )
    for response in (_camera("Nikon 5100 (NPL)", FINE), observer):
        reference = band_integrals(spectra, response)
        resampled = band_integrals(
            resample(spectra, coarse, method=method), resample(response, coarse, method=method)
        )
        assert np.abs(resampled / reference - 1).max() < 0.005


def test_box_downsampling_to_the_10_nm_grid_keeps_band_integrals_within_half_a_percent():
    coarse = WavelengthGrid.regular(380, 780, 10)
    spectra = _colorchecker_under_d65(FINE)
    response = _camera("Nikon 5100 (NPL)", FINE)
    reference = band_integrals(spectra, response)
    resampled = band_integrals(
        resample(spectra, coarse, method="box"), resample(response, coarse, method="box")
    )
    assert np.abs(resampled / reference - 1).max() < 0.005


def test_pchip_upsampling_keeps_band_integrals_within_half_a_percent():
    coarse = WavelengthGrid.regular(380, 780, 10)
    spectra = resample(_colorchecker_under_d65(FINE), coarse, method="box")
    response = resample(_camera("Nikon 5100 (NPL)", FINE), coarse, method="box")
    reference = band_integrals(spectra, response)
    upsampled = band_integrals(
        resample(spectra, FINE, method="pchip"), resample(response, FINE, method="pchip")
    )
    assert np.abs(upsampled / reference - 1).max() < 0.005


@settings(max_examples=40, deadline=None)
@given(
    values=st.lists(st.floats(0.0, 10.0), min_size=20, max_size=20),
    step=st.sampled_from([2.5, 5.0, 10.0, 20.0]),
)
def test_box_resampling_conserves_the_integral_over_the_cells(values, step):
    source = SampledSpectra(WavelengthGrid.regular(400, 780, 20), np.array(values))
    target = WavelengthGrid.regular(420, 760, step)
    box = resample(source, target, method="box")
    # Regular cells: width x mean summed over cells = exact integral of the linear interpolant.
    total = np.sum(box.values) * step
    start, stop = 420 - step / 2, 760 + step / 2
    knots = source.wavelengths_nm[(source.wavelengths_nm > start) & (source.wavelengths_nm < stop)]
    edges = np.concatenate([[start], knots, [stop]])
    exact = np.trapezoid(np.interp(edges, source.wavelengths_nm, source.values), edges)
    assert total == pytest.approx(exact, rel=1e-4, abs=1e-9)


def test_band_integrals_agree_with_colour_tristimulus_integration():
    grid = WavelengthGrid.regular(360, 830, 1)
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    sd = chart["red"].copy().align(colour.SpectralShape(360, 830, 1))
    illuminant = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(360, 830, 1))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    expected = colour.sd_to_XYZ(sd, cmfs, illuminant, method="Integration")
    ours = band_integrals(from_colour(sd) * from_colour(illuminant), from_colour(cmfs))
    normalization = band_integrals(from_colour(illuminant), from_colour(cmfs))[1]
    np.testing.assert_allclose(100 * ours / normalization, expected, rtol=2e-3)
    assert grid.size == from_colour(sd).grid.size


def test_colour_round_trip_is_exact():
    spectra = SampledSpectra(
        DEFAULT_GRID, np.random.default_rng(1).random((3, 33)), ("a", "b", "c")
    )
    msds = to_colour(spectra)
    assert isinstance(msds, colour.MultiSpectralDistributions)
    back = from_colour(msds)
    assert back.grid == spectra.grid and back.names == spectra.names
    np.testing.assert_array_equal(back.values, spectra.values)
    single = from_colour(to_colour(SampledSpectra(DEFAULT_GRID, spectra.values[0])))
    np.testing.assert_array_equal(single.values, spectra.values[0])
