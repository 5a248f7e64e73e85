"""``spectwin btf render``: a preview of any BTF store in a standard scene (issue 44).

Small BTF stores made by hand (9 x 9 gonioreflectometer-like directions on rings at 0, 30 and
60 degrees, 4 x 4 texels, 33 bands), rendered at 32 px and 4 spp: both presets on a plane and a
sphere, a cloth, a constant reflectance rendering in proportion to it (same seed: the same
random numbers), an imported RGB BTF, the PCA form, spectral and RGB environment maps; and bad
inputs, each refused in one line with nothing written."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import OpenEXR
import pytest
from scipy import ndimage
from typer.testing import CliRunner

from hwbridge.store import CaptureStore
from recon.btf.rgb_import import DIRECTION_TABLE, RGB_COLUMNS
from recon.btf.store import BTFStore, write_btf
from recon.spectra import DEFAULT_GRID, WavelengthGrid
from recon.spectral_exr import read_spectral_exr, write_spectral_exr
from twin.cli.app import app
from twin.validate.preview_geometry import Shape, surface_view

pytestmark = pytest.mark.render

runner = CliRunner()
PIXELS, SPP = 32, 4
RINGS: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (30.0, 0.0),
    (30.0, 90.0),
    (30.0, 180.0),
    (30.0, 270.0),
)
RINGS += ((60.0, 0.0), (60.0, 90.0), (60.0, 180.0), (60.0, 270.0))


def _run(*arguments):
    return runner.invoke(app, [str(argument) for argument in arguments], prog_name="spectwin")


def _direction(theta_deg: float, phi_deg: float) -> list[float]:
    theta, phi = np.radians(theta_deg), np.radians(phi_deg)
    return [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]


def _gonio_btf(path: Path, rho: float, textured: bool = False) -> Path:
    """A BTF of constant reflectance ``rho`` (``rho / pi`` per sr) on the rings' product set;
    ``textured``: times a texture and a spectral slope."""
    directions = np.array([_direction(*ring) for ring in RINGS])
    lights, views = np.meshgrid(np.arange(len(RINGS)), np.arange(len(RINGS)), indexing="ij")
    values = np.full((lights.size, 4, 4, DEFAULT_GRID.size), rho / np.pi, np.float32)
    if textured:
        texture = 0.5 + np.random.default_rng(0).random((1, 4, 4, 1))
        values *= (texture * np.linspace(0.5, 1.5, DEFAULT_GRID.size)).astype(np.float32)
    write_btf(
        path,
        values,
        DEFAULT_GRID,
        light_dirs=directions[lights.ravel()],
        view_dirs=directions[views.ravel()],
        material="test_sample",
    )
    return path


def _rgb_folder(root: Path) -> Path:
    """sRGB images (4 x 4, a reddish brown) of the rings' 81 pairs with their directions.csv
    (the gonio BTFs' directions and size: the renderer's compiled kernel is reused)."""
    images = root / "rgb_images"
    images.mkdir()
    rows = [",".join(RGB_COLUMNS)]
    for number, (light, view) in enumerate((light, view) for light in RINGS for view in RINGS):
        cv2.imwrite(str(images / f"{number}.png"), np.full((4, 4, 3), (60, 90, 170), np.uint8))
        rows.append(f"{number}.png,{light[0]},{light[1]},{view[0]},{view[1]}")
    (images / DIRECTION_TABLE).write_text("\n".join(rows) + "\n")
    return images


def _rgb_exr(path: Path, height: int, width: int) -> Path:
    pixels = np.full((height, width), 0.5, np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {"R": pixels, "G": pixels * 0.9, "B": pixels * 0.8}
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))
    return path


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("btf_render")
    _gonio_btf(root / "rho20.btf.zarr", 0.2)
    _gonio_btf(root / "rho40.btf.zarr", 0.4)
    _gonio_btf(root / "textured.btf.zarr", 0.4, textured=True)
    shutil.copytree(root / "textured.btf.zarr", root / "pca.btf.zarr")
    compressed = _run("compress", root / "pca.btf.zarr", "--brightness", 4, "--spectral", 3)
    assert compressed.exit_code == 0, compressed.output
    imported = _run("btf", "import", _rgb_folder(root), "--out", root / "rgb.btf.zarr", "--json")
    assert imported.exit_code == 0, imported.output
    sky = np.full((8, 16, DEFAULT_GRID.size), 0.5, np.float32)
    write_spectral_exr(root / "sky.exr", sky, DEFAULT_GRID)
    write_spectral_exr(root / "square.exr", sky[:, :8, :5], WavelengthGrid(np.arange(5.0) + 500))
    _rgb_exr(root / "rgb_sky.exr", 8, 16)
    (root / "notes.exr").write_text("not an image\n")
    incomplete = BTFStore.create(
        root / "incomplete.btf.zarr",
        light_dirs=np.array([[0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)]]),
        view_dirs=np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]),
        texels=4,
        grid=DEFAULT_GRID,
        material="test_sample",
    )
    incomplete.write_pair(0, np.full((4, 4, DEFAULT_GRID.size), 0.1))
    CaptureStore.create(
        root / "run.capture.zarr",
        rig={"rig": "gonioreflectometer", "program": "test"},
        backend="sim",
        seed=1,
        plan=[{"camera": "k4", "kind": "dark", "exposure_s": 0.5, "band_nm": 500.0}],
        cameras={"k4": (8, 8)},
    )
    garbled = root / "garbled.btf.zarr"
    shutil.copytree(root / "rho20.btf.zarr", garbled)
    (garbled / "zarr.json").write_text("{ not json")
    return root


def _render(store: Path, out: Path, *options: object) -> dict:
    result = _run("btf", "render", store, "--out", out, "--pixels", PIXELS, "--spp", SPP, *options)
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    summary = json.loads((out / "render.json").read_text())
    if "--json" in options:
        assert json.loads(result.stdout)["form"] == summary["form"]
    else:
        line = result.stdout.strip().splitlines()[-1]
        assert line.startswith(f"rendered {summary['material']}") and "extrapolated" in line
    return summary


def _sample_mean(out: Path, shape: Shape) -> np.ndarray:
    """The spectral EXR's mean over the sample's pixels, per band."""
    image = read_spectral_exr(out / "render.exr")
    assert image.cube.shape == (PIXELS, PIXELS, DEFAULT_GRID.size)
    assert np.all(np.isfinite(image.cube))
    return image.cube[surface_view(shape, PIXELS).mask].mean(axis=0)


@pytest.mark.parametrize(("preset", "shape"), [("studio", "plane"), ("daylight", "sphere")])
def test_renders_png_and_spectral_exr_of_each_preset(inputs, tmp_path, preset, shape):
    out = tmp_path / "preview"
    summary = _render(
        inputs / "textured.btf.zarr", out, "--preset", preset, "--shape", shape, "--json"
    )
    assert summary["form"].startswith("decoded") and summary["measured_as"] == "spectral"
    assert summary["shape"] == shape and summary["lighting"].startswith(preset)
    assert summary["sample_pixels"] > 50 and summary["render_s"] >= 0
    # the sphere's rim is seen beyond the BTF's largest view angle (60 degrees)
    grazing = any(line.startswith("views beyond 60 deg") for line in summary["extrapolated"])
    assert grazing == (shape == "sphere")
    mean = _sample_mean(out, shape)
    assert np.all(mean > 0)
    png = cv2.imread(str(out / "render.png"))
    assert png.shape == (PIXELS, PIXELS, 3) and png.max() > 0
    assert sorted(path.name for path in out.iterdir()) == [
        "render.exr",
        "render.json",
        "render.png",
    ]


def test_a_constant_reflectance_renders_in_proportion_to_it(inputs, tmp_path):
    means = []
    for rho in (20, 40):
        _render(inputs / f"rho{rho}.btf.zarr", tmp_path / f"r{rho}")
        means.append(_sample_mean(tmp_path / f"r{rho}", "plane"))
    np.testing.assert_allclose(means[1] / means[0], 2.0, rtol=0.01)


def test_the_cloth_renders_in_proportion_to_the_reflectance(inputs, tmp_path):
    """On the cloth too a constant BTF at twice the reflectance renders at twice the radiance,
    but for the light the cloth throws on itself in its folds (rho squared after one bounce):
    the ratio is 2 (1 + f) / (1 + f / 2) for the share f of the radiance at rho 0.4 that comes
    from the cloth, a few per cent."""
    summaries, means = [], []
    for rho in (20, 40):
        summaries.append(
            _render(inputs / f"rho{rho}.btf.zarr", tmp_path / f"c{rho}", "--shape", "cloth")
        )
        means.append(_sample_mean(tmp_path / f"c{rho}", "cloth"))
    ratio = means[1] / means[0]
    assert np.all(ratio >= 2.0 * 0.995) and np.all(ratio <= 2.0 * 1.06), ratio
    mask = surface_view("cloth", PIXELS).mask
    assert summaries[0]["shape"] == "cloth"
    assert summaries[0]["sample_pixels"] == mask.sum() > 0.2 * PIXELS**2
    png = cv2.imread(str(tmp_path / "c40" / "render.png"))
    assert png.shape == (PIXELS, PIXELS, 3) and png[mask].max() > 0
    assert (tmp_path / "c40" / "render.exr").is_file()
    # the rim lamp, behind the rod, meets the cloth's visible side beyond the BTF's largest
    # light angle (60 degrees) wherever it lights it
    extrapolated = summaries[0]["extrapolated"]
    assert "rim beyond 60 deg on 100 % of the lit sample" in extrapolated, extrapolated


def test_the_cloth_is_seen_where_its_mask_says(inputs, tmp_path):
    """The pixels whose radiance doubles with the reflectance are those of the sample's mask,
    but on its outline (pixels the cloth covers in part)."""
    for rho in (20, 40):
        _render(inputs / f"rho{rho}.btf.zarr", tmp_path / f"m{rho}", "--shape", "cloth")
    low, high = (
        read_spectral_exr(tmp_path / f"m{rho}" / "render.exr").cube.mean(axis=2) for rho in (20, 40)
    )
    doubled = high > 1.5 * low
    mask = surface_view("cloth", PIXELS).mask
    assert doubled[ndimage.binary_erosion(mask)].all()
    assert not doubled[~ndimage.binary_dilation(mask)].any()


def test_an_imported_rgb_btf_and_the_pca_form_render(inputs, tmp_path):
    rgb = _render(inputs / "rgb.btf.zarr", tmp_path / "rgb")
    assert rgb["measured_as"].startswith("RGB")
    assert np.all(_sample_mean(tmp_path / "rgb", "plane") > 0)
    pca = _render(inputs / "pca.btf.zarr", tmp_path / "pca")
    assert pca["form"].startswith("PCA")
    assert np.all(_sample_mean(tmp_path / "pca", "plane") > 0)


def test_spectral_and_rgb_environment_maps_light_the_sample(inputs, tmp_path):
    spectral = _render(
        inputs / "textured.btf.zarr", tmp_path / "e", "--environment", inputs / "sky.exr"
    )
    assert spectral["environment_note"] is None
    assert np.all(_sample_mean(tmp_path / "e", "plane") > 0)
    rgb = _render(
        inputs / "textured.btf.zarr", tmp_path / "f", "--environment", inputs / "rgb_sky.exr"
    )
    assert "upsampled" in rgb["environment_note"]
    assert np.all(_sample_mean(tmp_path / "f", "plane") > 0)


def test_shape_help_lists_the_cloth():
    result = _run("btf", "render", "--help")
    assert result.exit_code == 0
    assert "cloth" in " ".join(result.stdout.split())


def _busy(out: Path) -> None:
    out.mkdir()
    (out / "old.txt").write_text("mine\n")


# name: (store, extra options with {inputs} filled in, what the one line says, set-up of --out);
# exit code 2 (bad input) but for RUN_ERRORS (1)
BAD = {
    "not a BTF store": ("notes.exr", (), "expected a BTF store", None),
    "a capture store": ("run.capture.zarr", (), "not a BTF store", None),
    "an incomplete store": ("incomplete.btf.zarr", (), "incomplete BTF store", None),
    "unknown preset": ("rho20.btf.zarr", ("--preset", "noon"), "--preset", None),
    "preset and environment": (
        "rho20.btf.zarr",
        ("--preset", "studio", "--environment", "{inputs}/sky.exr"),
        "expected one light",
        None,
    ),
    "environment not an EXR": (
        "rho20.btf.zarr",
        ("--environment", "{inputs}/notes.exr"),
        "not an OpenEXR file",
        None,
    ),
    "environment missing": (
        "rho20.btf.zarr",
        ("--environment", "{inputs}/nothing.exr"),
        "no such file",
        None,
    ),
    "spectral environment not 2:1": (
        "rho20.btf.zarr",
        ("--environment", "{inputs}/square.exr"),
        "twice as wide",
        None,
    ),
    "unknown shape": ("rho20.btf.zarr", ("--shape", "cube"), "--shape", None),
    "pixels 0": ("rho20.btf.zarr", ("--pixels", "0"), "--pixels", None),
    "pixels negative": ("rho20.btf.zarr", ("--pixels", "-8"), "--pixels", None),
    "spp 0": ("rho20.btf.zarr", ("--spp", "0"), "--spp", None),
    "output folder not empty": ("rho20.btf.zarr", (), "not empty", _busy),
    "missing store": ("nothing.btf.zarr", (), "nothing.btf.zarr", None),
    # a store whose metadata is damaged is a run error (exit 1), as for every command
    "unreadable store metadata": ("garbled.btf.zarr", (), "damaged store", None),
}
RUN_ERRORS = {"unreadable store metadata"}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_is_one_line_and_writes_nothing(inputs, tmp_path, name):
    store, options, says, setup = BAD[name]
    out = tmp_path / "out"
    if setup is not None:
        setup(out)
    before = sorted(out.iterdir()) if out.exists() else None
    filled = [option.format(inputs=inputs) for option in options]
    result = _run("btf", "render", inputs / store, "--out", out, *filled)
    assert result.exit_code == (1 if name in RUN_ERRORS else 2), result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert says in lines[0]
    assert (sorted(out.iterdir()) if out.exists() else None) == before
