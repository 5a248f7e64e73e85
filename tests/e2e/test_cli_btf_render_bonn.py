"""An RGB BTF from a file of the Bonn database's UBO2003 layout, written here, imported with
``spectwin btf import`` and previewed with ``spectwin btf render`` (issue 44): a grey of linear
value 0.4 renders as a hand-made BTF of constant reflectance 0.4 does (the same scene, seed and
samples; a constant BTF's rendering does not depend on its directions)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from recon.btf.store import write_btf
from recon.spectra import DEFAULT_GRID
from recon.spectral_exr import read_spectral_exr
from twin.cli.app import app
from twin.validate.preview_geometry import surface_view

pytestmark = pytest.mark.render

runner = CliRunner()
PIXELS, SPP = 32, 4
GREY = 0.4


def _run(*arguments):
    result = runner.invoke(app, [str(a) for a in arguments], prog_name="spectwin")
    assert result.exit_code == 0, result.output
    return result


def _sample_mean(out: Path) -> np.ndarray:
    image = read_spectral_exr(out / "render.exr")
    return image.cube[surface_view("plane", PIXELS).mask].mean(axis=0)


def test_a_bonn_file_imports_and_renders_as_its_reflectance(tmp_path, bonn_files):
    ring = [(0.0, 0.0), (30.0, 90.0), (60.0, 225.0)]  # polar, azimuth (degrees)
    angles = np.array([[*light, *view] for light in ring for view in ring])
    encoded = np.round(255 * bonn_files._srgb_encode(np.full((9, 6, 8, 3), GREY)))
    bonn_files.write_ubo2003(tmp_path / "grey.zip", angles, encoded.astype(np.uint8))
    _run("btf", "import", tmp_path / "grey.zip", "--out", tmp_path / "grey.btf.zarr")
    directions = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, np.sqrt(0.75)]])
    lights, views = np.meshgrid([0, 1], [0, 1], indexing="ij")
    write_btf(
        tmp_path / "constant.btf.zarr",
        np.full((4, 4, 4, DEFAULT_GRID.size), GREY / np.pi, np.float32),
        DEFAULT_GRID,
        light_dirs=directions[lights.ravel()],
        view_dirs=directions[views.ravel()],
        material="test_sample",
    )
    means = {}
    for name in ("grey", "constant"):
        out = tmp_path / f"{name}_render"
        store = tmp_path / f"{name}.btf.zarr"
        _run("btf", "render", store, "--out", out, "--pixels", PIXELS, "--spp", SPP)
        means[name] = _sample_mean(out)
    summary = json.loads((tmp_path / "grey_render" / "render.json").read_text())
    assert "UBO2003" in summary["measured_as"]
    # 8-bit sRGB of 0.4 reads back as 0.402; Jakob 2019's grey is flat within 1 %.
    np.testing.assert_allclose(means["grey"].mean(), means["constant"].mean(), rtol=0.03)
