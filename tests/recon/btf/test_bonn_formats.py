"""The Bonn BTF database's layouts (recon.btf.bonn_formats): files written to the documented
layouts (scripts/bonn_btf_files.py) decode to the images they were made from, pair by pair and
the right way up, and broken files fail in one line. The same files decode identically in
btf-extractor 1.7.0 (``bonn_btf_files.py compare``; BENCHMARKS.md)."""

import zipfile

import numpy as np
import pytest

from recon.btf.bonn_formats import read_image_archive, read_ubo2014
from recon.btf.rgb_import import import_rgb_images, rgb_source
from recon.errors import InputError

_HEIGHT, _WIDTH = 6, 8  # not square: a transposed or unflipped reader shows


def _directions_rad():
    return np.radians([[0.0, 0.0], [30.0, 90.0], [60.0, 225.0]])


def _images(rng, count=3):
    """``(light, view, H, W, 3)`` linear RGB: a texture whose rows, columns and colours all
    differ, scaled differently per pair."""
    rows, columns = np.mgrid[0:_HEIGHT, 0:_WIDTH]
    texture = 0.1 + 0.8 * np.stack(
        [rows / _HEIGHT, columns / _WIDTH, (rows * _WIDTH + columns) / (_HEIGHT * _WIDTH)], -1
    )
    return (0.3 + 0.7 * rng.random((count, count, 1, 1, 3))) * texture


def _archive_angles():
    directions = np.degrees(_directions_rad())
    return np.array([[*light, *view] for light in directions for view in directions])


def test_ubo2014_in_double_precision_decodes_to_its_images_by_light_then_view(
    tmp_path, rng, bonn_files
):
    images = _images(rng)
    path = tmp_path / "x.btf"
    bonn_files.write_ubo2014(path, _directions_rad(), _directions_rad(), images, scalar_size=8)
    read = read_ubo2014(path)
    assert read.layout == "UBO2014" and read.encoding == "linear" and read.n_pairs == 9
    np.testing.assert_allclose(read.angles_deg[5], [30.0, 90.0, 60.0, 225.0], atol=1e-4)
    for pair, (light, view) in enumerate(np.ndindex(3, 3)):
        np.testing.assert_allclose(read.read(pair), images[light, view], atol=1e-6)


@pytest.mark.parametrize(
    ("options", "atol"),
    [
        ({"scalar_size": 2}, 1e-3),  # half floats: 11 significant bits
        ({"scalar_size": 4, "colour_model": 11, "rotations": True, "version": 4}, 1e-5),
    ],
)
def test_ubo2014_half_floats_yuv_rotations_and_newer_headers_decode(
    tmp_path, rng, bonn_files, options, atol
):
    images = _images(rng)
    path = tmp_path / "x.btf"
    bonn_files.write_ubo2014(path, _directions_rad(), _directions_rad(), images, **options)
    decoded = read_ubo2014(path)
    np.testing.assert_allclose(decoded.read(7), images[2, 1], atol=atol)


def test_ubo2003_archive_has_sorted_whole_degree_pairs_and_srgb_decoded_images(
    tmp_path, rng, bonn_files
):
    images = _images(rng).reshape(-1, _HEIGHT, _WIDTH, 3)
    encoded = np.round(255 * bonn_files._srgb_encode(images)).astype(np.uint8)
    order = np.arange(9)[::-1]  # written in reverse: the reader sorts by angle
    path = tmp_path / "x.zip"
    bonn_files.write_ubo2003(path, _archive_angles()[order], encoded[order], folder="SAMPLE/")
    read = read_image_archive(path)
    assert read.layout == "UBO2003" and read.encoding == "sRGB"
    np.testing.assert_array_equal(read.angles_deg, _archive_angles().round())
    decoded = np.stack([read.read(pair) for pair in range(9)])
    # JPEG at quality 95 without chroma subsampling: within 2 % on average.
    assert np.abs(decoded - images).mean() < 0.02


def test_atrium_hdr_archive_is_read_the_right_way_up(tmp_path, rng, bonn_files):
    images = _images(rng).reshape(-1, _HEIGHT, _WIDTH, 3)
    path = tmp_path / "x.zip"
    bonn_files.write_atrium_hdr(path, _archive_angles(), images)
    read = read_image_archive(path)
    assert read.layout == "ATRIUM HDR" and read.encoding == "linear"
    # RGBE: 8-bit mantissas of a shared exponent, steps of 1/256 below 1
    np.testing.assert_allclose(read.read(4), images[4], atol=1 / 256)


def test_a_ubo2014_import_is_an_rgb_store_of_reduced_texels(tmp_path, rng, bonn_files):
    images = _images(rng)
    path = tmp_path / "wool.btf"
    bonn_files.write_ubo2014(path, _directions_rad(), _directions_rad(), images)
    store = import_rgb_images(path, tmp_path / "x.btf.zarr", texels=4)
    assert store.complete and store.material == "wool" and store.texels == (3, 4)
    assert store.n_pairs == 9
    source = rgb_source(store)
    assert (source.layout, source.encoding, source.texel_reduction) == (
        "UBO2014",
        "linear",
        2,
    )


def _truncated(path, data):
    path.write_bytes(data[:-7])


def _trailing(path, data):
    path.write_bytes(data + b"\0\0")


def _signature(path, data):
    path.write_bytes(b"!FMF16FC" + data[9:])


def _colour_model(path, data):
    # signature, version-1 header, three views of three lights, width and height, components
    position = 9 + 264 + 4 + 3 * (8 + 4 + 3 * 8) + 8 + 4
    path.write_bytes(data[:position] + (5).to_bytes(4, "little") + data[position + 4 :])


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (_truncated, "ends at byte"),
        (_trailing, "bytes after the last channel"),
        (_signature, "expected b'!DFMF08FC'"),
        (_colour_model, "colour model 5"),
    ],
)
def test_a_broken_ubo2014_file_fails_in_one_line(tmp_path, rng, bonn_files, damage, message):
    good = tmp_path / "good.btf"
    bonn_files.write_ubo2014(good, _directions_rad(), _directions_rad(), _images(rng))
    bad = tmp_path / "bad.btf"
    damage(bad, good.read_bytes())
    with pytest.raises(InputError, match=message) as error:
        read_ubo2014(bad)
    assert "\n" not in str(error.value)


def test_bad_archives_fail_in_one_line(tmp_path, rng, bonn_files):
    empty = tmp_path / "empty.zip"
    with zipfile.ZipFile(empty, "w") as archive:
        archive.writestr("readme.txt", "no images")
    with pytest.raises(InputError, match="no images named like"):
        read_image_archive(empty)
    encoded = np.zeros((2, 4, 4, 3), np.uint8)
    twice = tmp_path / "twice.zip"
    angles = np.array([[0, 0, 0, 0], [0, 0, 0, 0]])
    bonn_files.write_ubo2003(twice, angles[:1], encoded[:1], folder="a/")
    with zipfile.ZipFile(twice, "a") as archive:
        archive.writestr("b/tl000 pl000 tv000 pv000.jpg", archive.read(archive.namelist()[0]))
    with pytest.raises(InputError, match="have the same angles"):
        read_image_archive(twice)
    below = tmp_path / "below.zip"
    bonn_files.write_ubo2003(below, np.array([[90, 0, 0, 0]]), encoded[:1])
    with pytest.raises(InputError, match="expected 0 to below 90"):
        read_image_archive(below)
    (tmp_path / "junk.zip").write_bytes(b"not a zip")
    with pytest.raises(InputError, match="not a readable zip archive"):
        read_image_archive(tmp_path / "junk.zip")
