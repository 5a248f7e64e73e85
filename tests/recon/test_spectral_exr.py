"""Spectral OpenEXR in the Fichet, Pacanowski and Wilkie (2021) layout (recon.spectral_exr)."""

import colour
import numpy as np
import OpenEXR
import pytest

from recon.errors import InputError, MissingDataError
from recon.spectra import DEFAULT_GRID, WavelengthGrid
from recon.spectral_exr import channel_name, read_spectral_exr, write_spectral_exr


@pytest.mark.parametrize("dtype", [np.float32, np.float16])
def test_round_trip_is_bit_exact_with_layout_channel_names(tmp_path, rng, dtype):
    cube = (rng.random((9, 13, 33)) * 50).astype(dtype)
    path = write_spectral_exr(
        tmp_path / "radiance.exr", cube, DEFAULT_GRID, attributes={"source": "test"}
    )
    with OpenEXR.File(str(path)) as exr:
        names = set(exr.channels())
        header = dict(exr.header())
        assert header["spectralLayoutVersion"] == "1.0"
        assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert names == {f"S0.{w:d},0nm" for w in range(400, 721, 10)}
    image = read_spectral_exr(path)
    assert image.cube.dtype == dtype and image.kind == "emissive" and image.grid == DEFAULT_GRID
    np.testing.assert_array_equal(
        image.cube.view(np.uint16 if dtype == np.float16 else np.uint32),
        cube.view(np.uint16 if dtype == np.float16 else np.uint32),
    )
    assert image.attributes["source"] == "test"


def test_reflective_images_use_t_channels_and_fractional_wavelengths(tmp_path, rng):
    grid = WavelengthGrid(np.array([412.5, 450.0, 487.25]))
    cube = rng.random((4, 5, 3)).astype(np.float32)
    path = write_spectral_exr(tmp_path / "reflectance.exr", cube, grid, kind="reflective")
    assert channel_name(412.5, "reflective") == "T.412,5nm"
    image = read_spectral_exr(path)
    assert image.kind == "reflective" and image.grid == grid
    np.testing.assert_array_equal(image.cube, cube)


def test_colour_reads_our_files_as_the_same_spectral_image(tmp_path, rng):
    """Independent peer: colour's Fichet et al. (2021) reader (through OpenImageIO)."""
    cube = rng.random((6, 7, 33)).astype(np.float32)
    path = write_spectral_exr(tmp_path / "peer.exr", cube, DEFAULT_GRID)
    components = colour.io.read_spectral_image_Fichet2021(str(path))
    wavelengths, values = components["S0"]
    np.testing.assert_array_equal(wavelengths, DEFAULT_GRID.wavelengths_nm)
    np.testing.assert_array_equal(values, cube)


def test_bad_cubes_are_rejected_and_nothing_is_written(tmp_path, rng):
    target = tmp_path / "bad.exr"
    with pytest.raises(InputError, match=r"\(H, W, 33\)"):
        write_spectral_exr(target, rng.random((4, 5, 32)).astype(np.float32), DEFAULT_GRID)
    with pytest.raises(InputError, match="float32 or float16"):
        write_spectral_exr(target, rng.random((4, 5, 33)), DEFAULT_GRID)
    with pytest.raises(InputError, match="kind"):
        write_spectral_exr(
            target, rng.random((4, 5, 33)).astype(np.float32), DEFAULT_GRID, kind="x"
        )
    with pytest.raises(InputError, match="does not exist"):
        write_spectral_exr(
            tmp_path / "missing" / "a.exr", np.zeros((1, 1, 33), np.float32), DEFAULT_GRID
        )
    assert list(tmp_path.iterdir()) == []


def test_reading_files_without_spectral_channels_fails_clearly(tmp_path):
    rgb = tmp_path / "rgb.exr"
    channels = {name: np.zeros((2, 2), np.float32) for name in "RGB"}
    with OpenEXR.File(
        {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, channels
    ) as exr:
        exr.write(str(rgb))
    with pytest.raises(InputError, match="S0.550,0nm"):
        read_spectral_exr(rgb)
    with pytest.raises(MissingDataError):
        read_spectral_exr(tmp_path / "nothing.exr")
