"""Spectra from sRGB images (recon.rgb_upsampling): the sRGB response against colour's own
conversion, the Jakob 2019 table against colour's optimiser, and the spectralization's input
checks."""

import colour
import numpy as np
import pytest

from recon.errors import InputError
from recon.rgb_upsampling import read_srgb_image, srgb_response, upsample_srgb
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, from_colour, resample


def _checker() -> np.ndarray:
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    return np.stack([resample(from_colour(sd), DEFAULT_GRID).values for sd in chart.values()])


def test_srgb_response_gives_colours_linear_srgb_of_the_colour_checker():
    """Peer: colour's sd_to_XYZ (CIE 1931, D65) and XYZ_to_RGB (sRGB) of the same patches."""
    spectra = _checker()
    illuminant = colour.SDS_ILLUMINANTS["D65"]
    shape = colour.SpectralShape(400, 720, 10)
    expected = []
    for values in spectra:
        sd = colour.SpectralDistribution(values, shape.wavelengths)
        xyz = colour.sd_to_XYZ(sd, illuminant=illuminant, shape=shape) / 100
        expected.append(colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False))
    np.testing.assert_allclose(spectra @ srgb_response(), expected, atol=0.01)
    np.testing.assert_allclose(np.ones(DEFAULT_GRID.size) @ srgb_response(), 1.0)


def test_jakob2019_spectra_reproduce_the_image_colours_and_colours_optimiser():
    linear = np.clip(_checker() @ srgb_response(), 0, 1)[None]  # (1, 24, 3), in gamut
    spectra = upsample_srgb(linear, "jakob2019").values
    assert spectra.shape == (1, 24, DEFAULT_GRID.size) and spectra.min() >= 0
    # The spectra have the image's colours back (the table is interpolated: within 0.02).
    inside = (linear[0] > 0.02).all(axis=1) & (linear[0] < 0.98).all(axis=1)
    np.testing.assert_allclose((spectra @ srgb_response())[0][inside], linear[0][inside], atol=0.02)
    # Peer: colour's direct optimisation for one patch (orange), from its XYZ under D65.
    xyz = colour.RGB_to_XYZ(linear[0, 6], "sRGB", apply_cctf_decoding=False)
    direct = colour.recovery.XYZ_to_sd_Jakob2019(xyz, illuminant=colour.SDS_ILLUMINANTS["D65"])
    values = resample(from_colour(direct), DEFAULT_GRID).values
    assert np.abs(spectra[0, 6] - values).max() < 0.03


def test_spectralization_needs_its_spots_inside_the_image_and_one_spectrum_each():
    linear = np.full((4, 4, 3), 0.5)
    spectra = SampledSpectra(DEFAULT_GRID, np.full((2, DEFAULT_GRID.size), 0.5))
    with pytest.raises(InputError, match="outside the 4 x 4 image"):
        upsample_srgb(
            linear, "spectralization", known_pixels=[[0, 0], [4, 1]], known_spectra=spectra
        )
    with pytest.raises(InputError, match="2 spectra for 1 known pixels"):
        upsample_srgb(linear, "spectralization", known_pixels=[[0, 0]], known_spectra=spectra)
    short = SampledSpectra(WavelengthGrid.regular(450.0, 720.0, 10.0), np.full((2, 28), 0.5))
    with pytest.raises(InputError, match="cover 450-720 nm; expected at least 400-700"):
        upsample_srgb(linear, "spectralization", known_pixels=[[0, 0], [1, 1]], known_spectra=short)
    with pytest.raises(InputError, match="method: expected one of"):
        upsample_srgb(linear, "smits")


def test_read_srgb_image_refuses_what_is_not_an_rgb_image(tmp_path):
    path = tmp_path / "grey.png"
    from skimage import io

    io.imsave(path, np.zeros((4, 4), np.uint8), check_contrast=False)
    with pytest.raises(InputError, match="expected an 8- or 16-bit RGB image"):
        read_srgb_image(path)
    (tmp_path / "broken.png").write_bytes(b"not a png")
    with pytest.raises(InputError, match="not a readable image"):
        read_srgb_image(tmp_path / "broken.png")
