"""RGB BTFs from a folder of images with a direction table (recon.btf.rgb_import): the store's
directions are the table's, its spectra have the images' colours, it says it came from RGB, and a
bad table or image fails in one line."""

import colour
import numpy as np
import pytest
import tifffile

from recon.btf.rgb_import import RGB_COLUMNS, import_rgb_images, rgb_source
from recon.errors import InputError
from recon.metrics import delta_e94
from recon.rgb_upsampling import srgb_response
from recon.spectra import DEFAULT_GRID, from_colour, resample

_ANGLES = np.array([[30.0, 0.0, 0.0, 0.0], [45.0, 90.0, 30.0, 200.0], [60.0, 180.0, 60.0, 135.0]])


def _checker_texture() -> np.ndarray:
    chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    spectra = np.stack([resample(from_colour(sd), DEFAULT_GRID).values for sd in chart.values()])
    return spectra[np.arange(64).reshape(8, 8) % 24]  # (8, 8, 33) reflectance factors


def _write_folder(folder, factors=(1.0, 0.8, 0.6)):
    """Three 16-bit sRGB TIFF images of the chart texture, dimmed per pair, with their table."""
    folder.mkdir()
    truth = []
    lines = [",".join(RGB_COLUMNS)]
    for pair, (angles, factor) in enumerate(zip(_ANGLES, factors, strict=True)):
        texture = factor * _checker_texture()
        linear = np.clip(texture @ srgb_response(), 0, 1)
        encoded = colour.cctf_encoding(linear, function="sRGB")
        tifffile.imwrite(folder / f"img{pair}.tif", np.round(65535 * encoded).astype(np.uint16))
        lines.append(f"img{pair}.tif," + ",".join(f"{a:g}" for a in angles))
        truth.append(texture)
    (folder / "directions.csv").write_text("\n".join(lines) + "\n")
    return np.stack(truth)


def test_imported_rgb_btf_has_the_tables_directions_and_the_images_colours(tmp_path):
    truth = _write_folder(tmp_path / "rgb")
    store = import_rgb_images(tmp_path / "rgb", tmp_path / "x.btf.zarr", material="chart")
    assert store.complete and store.material == "chart" and store.texels == (8, 8)
    theta, phi = np.radians(_ANGLES[1, 2]), np.radians(_ANGLES[1, 3])
    np.testing.assert_allclose(
        store.view_dirs[1],
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
    )
    assert rgb_source(store).model_dump() == {
        "colour_space": "sRGB",
        "layout": "image folder",
        "encoding": "sRGB",
        "upsampling": "jakob2019",
        "texel_reduction": 1,
        "scale": 1.0,
        "images": str((tmp_path / "rgb").resolve()),
        "spectralized": None,
    }
    factors = np.pi * np.stack([store.read_pair(pair) for pair in range(3)]).astype(np.float64)
    # Back to linear sRGB: the images' colours within the table's interpolation.
    np.testing.assert_allclose(
        factors @ srgb_response(), np.clip(truth @ srgb_response(), 0, 1), atol=0.02
    )
    # Under D65 the colours agree; under the thesis's ten illuminants the upsampled spectra
    # are metamers of the chart's own (measured: mean Delta E94 0.66 under D65 alone, from the
    # table's interpolation; 1.25 over the ten; the colours back within 0.011).
    d65 = delta_e94(factors.reshape(-1, 33), truth.reshape(-1, 33), DEFAULT_GRID, "D65")
    assert d65.mean() < 1.0


def test_brightness_above_one_is_kept(tmp_path):
    _write_folder(tmp_path / "rgb")
    store = import_rgb_images(tmp_path / "rgb", tmp_path / "x.btf.zarr", scale=3.0)
    white = np.pi * store.read_pair(0)[np.unravel_index(18, (8, 8))]  # a white 9.5 texel
    assert 2.0 < white.mean() < 3.0


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("file,theta\nimg0.tif,1\n", "header"),
        (",".join(RGB_COLUMNS) + "\nimg0.tif,30,0,x,0\n", "expected four angles"),
        (",".join(RGB_COLUMNS) + "\nimg0.tif,95,0,0,0\n", "expected 0 to below 90"),
        (",".join(RGB_COLUMNS) + "\n", "no rows"),
    ],
)
def test_a_bad_direction_table_fails_in_one_line(tmp_path, table, message):
    _write_folder(tmp_path / "rgb")
    (tmp_path / "rgb" / "directions.csv").write_text(table)
    with pytest.raises(InputError, match=message) as error:
        import_rgb_images(tmp_path / "rgb", tmp_path / "x.btf.zarr")
    assert "\n" not in str(error.value)


def test_images_of_different_sizes_are_refused(tmp_path):
    _write_folder(tmp_path / "rgb")
    tifffile.imwrite(tmp_path / "rgb" / "img2.tif", np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(InputError, match="4 x 4 px, expected 8 x 8"):
        import_rgb_images(tmp_path / "rgb", tmp_path / "x.btf.zarr")
