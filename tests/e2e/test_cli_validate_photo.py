"""``spectwin validate --photo``: a measured BTF rendered where the user photographed the sample
(issue 44), from files alone.

- The twin's own path writes, for the Lego, the wallpaper and the red fabric, its photograph of
  the true material in its room and the captured map as files with the sample's corners; the
  validation from those files alone gives the twin path's Delta E94 (same camera, same seed:
  within 2 %).
- A photograph made by hand (a grey square of reflectance 0.5 under a uniform sky of known
  linear sRGB radiance, seen by a camera of known pose): a Lambertian BTF of that reflectance
  matches it to Delta E94 < 0.5 and the fitted exposure is 1; a BTF of reflectance 0.25 is
  found 2x too dark (exposure 0.5, given) and a BTF of another colour is far off.
- Bad input: one line, exit 2, nothing written.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from recon.btf.store import BTFStore, write_btf
from recon.image_spectralization import write_rgb_exr
from recon.spectra import DEFAULT_GRID
from recon.spectral_exr import write_spectral_exr
from twin.cli.app import app
from twin.rigs.hemisphere import sattler_directions
from twin.validate.panels import polygon_mask
from twin.validate.photo_camera import recover_camera, square_corners

pytestmark = pytest.mark.render

runner = CliRunner()
SMALL = ("--pixels", "32")
DIRECTIONS = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 4)))
SKY_SRGB = np.array([0.6, 0.5, 0.4])
WIDTH, HEIGHT = 48, 36
CORNERS = np.array([[14.0, 8.0], [35.0, 9.0], [38.0, 27.0], [10.0, 26.0]])
FOV_DEG = 50.0


def _run(*arguments):
    return runner.invoke(app, [str(argument) for argument in arguments], prog_name="spectwin")


def _store(path: Path, spectrum: np.ndarray, material: str, texels: int = 8) -> Path:
    """A BTF of one Lambertian spectrum (reflectance ``spectrum`` over pi) on every texel."""
    lights, views = np.meshgrid(np.arange(len(DIRECTIONS)), np.arange(len(DIRECTIONS)))
    values = np.broadcast_to(spectrum / np.pi, (lights.size, texels, texels, DEFAULT_GRID.size))
    write_btf(
        path,
        np.ascontiguousarray(values, np.float32),
        DEFAULT_GRID,
        light_dirs=DIRECTIONS[lights.ravel()],
        view_dirs=DIRECTIONS[views.ravel()],
        material=material,
    )
    return path


def _sky_spectrum() -> np.ndarray:
    """A smooth spectrum whose linear sRGB, seen through the CIE 1931 observer, is SKY_SRGB
    (least squares on three broad bumps)."""
    import colour

    from twin.validate.figure46 import cmfs_on

    wavelengths = DEFAULT_GRID.wavelengths_nm
    bumps = np.exp(-0.5 * ((wavelengths[None] - np.array([[450.0], [550.0], [620.0]])) / 40) ** 2)
    xyz_per_bump = bumps @ cmfs_on(DEFAULT_GRID) * (wavelengths[1] - wavelengths[0])
    srgb_per_bump = xyz_per_bump @ colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB.T
    weights = np.linalg.solve(srgb_per_bump.T, SKY_SRGB)
    return weights @ bumps


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("validate_photo")
    sky = _sky_spectrum()
    write_spectral_exr(
        root / "sky.exr", np.broadcast_to(sky, (32, 64, sky.size)).astype(np.float32), DEFAULT_GRID
    )
    # The camera that sees the square's corners at CORNERS; the photograph: the sky, and the
    # grey square of reflectance 0.5 over its interior (uniform light: radiance 0.5 x sky).
    focal = WIDTH / 2 / np.tan(np.radians(FOV_DEG) / 2)
    camera, _ = recover_camera(CORNERS, 1.0, WIDTH, HEIGHT, focal)
    exact = camera.project(square_corners(1.0))
    square = polygon_mask(exact, WIDTH, HEIGHT)
    photograph = np.where(square[..., None], 0.5 * SKY_SRGB, SKY_SRGB)
    write_rgb_exr(root / "photo.exr", photograph)
    write_rgb_exr(root / "black.exr", np.zeros_like(photograph))  # no exposure fits it
    (root / "corners.txt").write_text(";".join(f"{x!r},{y!r}" for x, y in exact))
    grey = np.ones(DEFAULT_GRID.size)
    _store(root / "grey50.btf.zarr", 0.5 * grey, "user_sample")
    _store(root / "grey25.btf.zarr", 0.25 * grey, "user_sample")
    _store(root / "green.btf.zarr", np.where(DEFAULT_GRID.wavelengths_nm < 560, 0.5, 0.05), "x")
    # A mirror sphere under the same sky, photographed by the same camera: the sky everywhere.
    disc = np.hypot(*np.meshgrid(np.arange(WIDTH) + 0.5 - 24, np.arange(HEIGHT) + 0.5 - 18)) < 12
    write_rgb_exr(root / "sphere.exr", np.where(disc[..., None], SKY_SRGB, 0.05))
    write_rgb_exr(root / "square.exr", np.ones((8, 8, 3)))
    (root / "notes.exr").write_text("not an image\n")
    return root


def _validate(store: Path, out: Path, *options: object) -> dict:
    result = _run("validate", store, "--out", out, *SMALL, "--json", *options)
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    return json.loads((out / "metrics.json").read_text())


def _photo_options(inputs: Path, *extra: object, spp: int = 256) -> tuple[object, ...]:
    """The options of a validation of the grey square's photograph at ``spp`` samples per pixel
    (the sky's spectrum is sampled by wavelength: 2 % noise per pixel at 16 spp)."""
    corners = (inputs / "corners.txt").read_text()
    return (
        "--photo",
        inputs / "photo.exr",
        "--environment",
        inputs / "sky.exr",
        "--sample-corners",
        corners,
        "--fov-deg",
        FOV_DEG,
        "--spp",
        spp,
        *extra,
    )


def test_a_btf_of_the_photographed_reflectance_matches_it(inputs, tmp_path):
    metrics = _validate(inputs / "grey50.btf.zarr", tmp_path / "out", *_photo_options(inputs))
    found = metrics["validation"]
    # A Lambertian square under a uniform sky: every path gives 0.5 x sky, no noise.
    assert found["mean_delta_e94_spectral"] < 0.5
    assert found["mean_delta_e94_rgb"] < 0.5
    assert metrics["exposure"] == pytest.approx(1.0, rel=0.01)
    assert metrics["corners_reprojection_px"] < 0.01
    # The BTF's lights reach 60 degrees; a uniform sky sends 1 - sin^2(60) = 25 % of its
    # cosine-weighted light from beyond.
    (beyond,) = [e for e in metrics["extrapolated"] if "sky's light from beyond 60 deg" in e]
    assert 20 <= int(beyond.split(" %")[0]) <= 30, beyond
    assert found["compared_pixels"] > 40  # of 24 x 18 rendered pixels
    assert (tmp_path / "out" / "validation.png").stat().st_size > 20_000


def test_a_wrong_btf_is_found_wrong(inputs, tmp_path):
    darker = _validate(
        inputs / "grey25.btf.zarr",
        tmp_path / "dark",
        *_photo_options(inputs, "--exposure", 0.5, spp=16),
    )
    # Exposure 0.5: the photograph's 0.5 x sky stands for 1.0 x sky, twice the BTF's 0.25.
    assert darker["validation"]["mean_delta_e94_spectral"] > 10  # measured 42.9 at 16 spp
    fitted = _validate(inputs / "grey25.btf.zarr", tmp_path / "fitted", *_photo_options(inputs))
    assert fitted["exposure"] == pytest.approx(2.0, rel=0.01)
    assert fitted["validation"]["mean_delta_e94_spectral"] < 0.5
    green = _validate(
        inputs / "green.btf.zarr", tmp_path / "green", *_photo_options(inputs, spp=16)
    )
    assert green["validation"]["mean_delta_e94_spectral"] > 10  # measured 15.7 at 16 spp


def test_the_light_from_a_mirror_sphere(inputs, tmp_path):
    options = _options(
        inputs,
        (
            "--environment",
            None,
            "--mirror-sphere",
            "{inputs}/sphere.exr",
            "--sphere-circle",
            "24,18,12",
        ),
    )
    metrics = _validate(inputs / "grey50.btf.zarr", tmp_path / "out", *options)
    # The sky's linear sRGB becomes spectra by Jakob 2019 times D65: its colour is kept, its
    # scale is the photograph's exposure.
    assert metrics["validation"]["mean_delta_e94_spectral"] < 1.0
    assert "mirror sphere" in metrics["environment_note"]


# The Lego bricks (relief: shading and occlusion in the photograph) and the colour chart (flat,
# and its per-field figures); the flat wallpaper and red fabric go through the chart's steps.
@pytest.mark.parametrize("material", ["lego", "colorchecker16"])
def test_the_file_path_gives_the_twin_paths_delta_e(inputs, tmp_path, material):
    store = _store(
        tmp_path / f"{material}.btf.zarr",
        np.linspace(0.2, 0.6, DEFAULT_GRID.size),
        material,
        texels=16,  # a chart field's 45/0 spot holds a texel
    )
    twin = _validate(store, tmp_path / "twin", "--map-height", 8, "--map-spp", 4, "--spp", 16)
    replay = twin["photo_inputs"]
    photo = _validate(
        store,
        tmp_path / "photo",
        "--photo",
        replay["photo"],
        "--environment",
        replay["environment"],
        "--sample-corners",
        replay["sample_corners"],
        "--fov-deg",
        replay["fov_deg"],
        "--exposure",
        1,
        "--spp",
        16,
    )
    assert photo["corners_reprojection_px"] < 0.01
    keys = ["mean_delta_e94_spectral", "mean_delta_e94_rgb", "median_delta_e94_spectral"]
    if material == "colorchecker16":  # the chart's per-field figures, from files too
        keys += ["field_mean_delta_e94_spectral", "field_mean_delta_e94_rgb"]
    for key in keys:
        assert photo["validation"][key] == pytest.approx(twin["figure46"][key], rel=0.02), key
    assert photo["validation"]["compared_pixels"] == twin["figure46"]["compared_pixels"]


def _busy(out: Path) -> None:
    out.mkdir()
    (out / "old.txt").write_text("mine\n")


# name: (options, with {inputs} filled in, what the one line says)
BAD = {
    "corners outside the photograph": (
        ("--sample-corners", "14,8;35,9;60,27;10,26"),
        "outside the 48 x 36 photograph",
    ),
    "three corners": (("--sample-corners", "14,8;35,9;38,27"), "expected four points"),
    "corners not numbers": (("--sample-corners", "a,b;c,d;e,f;g,h"), "expected four points"),
    "corners of no square": (("--sample-corners", "14,8;35,9;15,10;10,26"), "expected a square"),
    "corners seen from behind": (
        ("--sample-corners", "10,26;38,27;35,9;14,8"),
        "from behind",
    ),
    "no field of view": (("--fov-deg", None), "no 35 mm equivalent focal length"),
    "spp too few": (("--spp", "2"), "--spp"),
    "field of view too wide": (("--fov-deg", "170"), "expected 1 to 150 degrees"),
    "environment not an EXR": (("--environment", "{inputs}/notes.exr"), "not an OpenEXR file"),
    "environment not lat-long": (("--environment", "{inputs}/square.exr"), "twice as wide"),
    "photograph missing": (("--photo", "{inputs}/nothing.exr"), "no such file"),
    "photograph not an image": (("--photo", "{inputs}/corners.txt"), "expected a linear"),
    "unknown camera": (("--camera", "Brownie 127"), "Brownie 127"),
    "sphere circle outside": (
        (
            "--environment",
            None,
            "--mirror-sphere",
            "{inputs}/sphere.exr",
            "--sphere-circle",
            "40,18,12",
        ),
        "not inside the 48 x 36 photograph",
    ),
    "sphere photograph of another size": (
        (
            "--environment",
            None,
            "--mirror-sphere",
            "{inputs}/square.exr",
            "--sphere-circle",
            "4,4,3",
        ),
        "expected the photograph's 48 x 36",
    ),
    "sphere without its circle": (
        ("--environment", None, "--mirror-sphere", "{inputs}/sphere.exr"),
        "expected both",
    ),
    "two lights": (("--mirror-sphere", "{inputs}/sphere.exr"), "one light"),
    "negative exposure": (("--exposure", "-1"), "expected a positive factor"),
    "black photograph": (("--photo", "{inputs}/black.exr"), "the fitted exposure is 0;"),
}


def _options(inputs: Path, changes: tuple) -> list[str]:
    """The good options with ``changes`` (option, value; value None: left out)."""
    given = dict(zip(_photo_options(inputs)[::2], _photo_options(inputs)[1::2], strict=True))
    for option, value in zip(changes[::2], changes[1::2], strict=True):
        given[option] = value
    return [
        str(part).format(inputs=inputs)
        for option, value in given.items()
        if value is not None
        for part in (option, value)
    ]


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_is_one_line_and_writes_nothing(inputs, tmp_path, name):
    changes, says = BAD[name]
    out = tmp_path / "out"
    result = _run("validate", inputs / "grey50.btf.zarr", "--out", out, *_options(inputs, changes))
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert says in lines[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("options", "says"),
    [
        (("--environment", "{inputs}/sky.exr"), "only with --photo"),
        (("--photo", "{inputs}/photo.exr"), "expected --sample-corners and one light"),
    ],
)
def test_options_of_a_photo_go_together(inputs, tmp_path, options, says):
    filled = [str(option).format(inputs=inputs) for option in options]
    result = _run("validate", inputs / "grey50.btf.zarr", "--out", tmp_path / "out", *filled)
    assert result.exit_code == 2, result.output
    assert says in result.stderr


def test_a_store_of_no_twin_material_needs_a_photograph(inputs, tmp_path):
    result = _run("validate", inputs / "grey50.btf.zarr", "--out", tmp_path / "out")
    assert result.exit_code == 2, result.output
    assert "expected --photo and --environment" in result.stderr
    assert BTFStore.open(inputs / "grey50.btf.zarr").material == "user_sample"
