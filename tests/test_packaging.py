"""The product is self-contained: the wheel carries every scene and data file the code loads, it
runs from any folder without the repository, and no module refers to a path outside its package."""

import ast
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("twin", "recon", "hwbridge", "scenes")
DATA_FOLDERS = ("scenes", "hwbridge/mappings", "recon/data")


def _escaping_path_expressions(path: Path, package_root: Path) -> list[str]:
    """Source snippets of ``path`` that climb out of its top-level package or name an outside
    folder: ``Path(__file__).parents[n]`` / ``.parent.parent...`` past the package's root, and
    string constants with ``../`` or ``shared/data``."""
    source = path.read_text()
    # Directory levels from the module's folder up to the package's root, both included.
    levels = len(path.parent.relative_to(package_root.parent).parts)
    offenders, inner_links = [], set()
    for node in ast.walk(ast.parse(source, filename=str(path))):  # outer nodes come first
        if id(node) in inner_links:
            continue
        climbed = None
        if (
            isinstance(node, ast.Subscript)
            and isinstance(node.value, ast.Attribute)
            and node.value.attr == "parents"
            and isinstance(node.slice, ast.Constant)
        ):
            climbed, base = node.slice.value + 1, node.value.value
        elif isinstance(node, ast.Attribute) and node.attr == "parent":
            climbed, base = 0, node
            while isinstance(base, ast.Attribute) and base.attr == "parent":
                inner_links.add(id(base))
                climbed, base = climbed + 1, base.value
        # ``climbed`` steps up from the file: 1 is the module's folder, ``levels`` the package's.
        if climbed is not None and "__file__" in ast.unparse(base) and climbed > levels:
            offenders.append(ast.get_source_segment(source, node))
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = node.value
            if "../" in text or "..\\" in text or "shared/data" in text:
                offenders.append(repr(text[:60]))
    return offenders


def test_no_module_refers_to_a_path_outside_its_package():
    offenders = {
        str(path.relative_to(ROOT)): found
        for package in PACKAGES
        for path in sorted((ROOT / package).rglob("*.py"))
        if (found := _escaping_path_expressions(path, ROOT / package))
    }
    assert offenders == {}


def test_the_path_check_catches_a_module_that_leaves_its_package(tmp_path):
    module = tmp_path / "pkg" / "sub" / "mod.py"
    module.parent.mkdir(parents=True)
    module.write_text(
        "from pathlib import Path\n"
        "INSIDE = Path(__file__).resolve().parents[1] / 'x'\n"  # pkg/: allowed
        "OUTSIDE = Path(__file__).resolve().parents[2] / 'shared'\n"
        "UP = Path(__file__).parent.parent.parent\n"
        "ENV = '../shared/data'\n"
    )
    found = _escaping_path_expressions(module, tmp_path / "pkg")
    assert len(found) == 3 and not any("parents[1]" in item for item in found)


def _shipped_files() -> set[str]:
    """Every data file under the package data folders, as wheel member names."""
    return {
        str(path.relative_to(ROOT))
        for folder in DATA_FOLDERS
        for path in (ROOT / folder).rglob("*")
        if path.is_file() and path.suffix not in (".py", ".pyc") and "__pycache__" not in path.parts
    }


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation"]
        + ["--wheel-dir", str(out), str(ROOT)],
        check=True,
        capture_output=True,
        cwd=out,
    )
    (built,) = out.glob("spectwin-*.whl")
    return built


def test_the_wheel_contains_the_scenes_and_data_the_code_loads(wheel):
    members = set(zipfile.ZipFile(wheel).namelist())
    shipped = _shipped_files()
    assert shipped - members == set()
    # What the loaders read, named explicitly (a glob above would pass on an empty folder).
    for name in (
        "scenes/rigs/gonio.yaml",
        "scenes/rigs/dome.yaml",
        "scenes/cameras/coolsnap_k4.yaml",
        "scenes/cameras/basler_ccd12.yaml",
        "recon/data/real/emva1288_basler_ccd12/EMVA1288_Data.txt",
        "recon/data/real/emva1288_basler_ccd12/images/d_s_000_snap_049.png",
        "scenes/materials/colorchecker16.yaml",
        "scenes/sweeps/gonio_lamp_filter_sampling.yaml",
        "scenes/sweeps/dome_schedule_tbase_filter.yaml",
        "hwbridge/mappings/llanos2019.yaml",
        "recon/data/spectra/sensors/nikon_d70_rgb.csv",
        "recon/data/spectra/lights/tungsten_lab.csv",
        "recon/data/real/llanos2019/multispectral_images/sensor.mat",
        "recon/data/real/llanos2019/spectral_data/spectra_averaged.csv",
    ):
        assert name in members
    # Every data folder names its source and licence.
    for folder in (
        "scenes/",
        "recon/data/spectra/",
        "recon/data/real/llanos2019/",
        "recon/data/real/emva1288_basler_ccd12/",
    ):
        assert f"{folder}SOURCES.md" in members
    assert len([m for m in members if m.startswith("recon/data/real/llanos2019/")]) > 60


def test_the_installed_wheel_runs_from_another_folder_without_the_repository(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(target)]
        + [str(wheel)],
        check=True,
        capture_output=True,
    )
    code = (
        "import json, twin, recon, scenes, hwbridge\n"
        "from twin.rigs.rig_config import available_rigs, load_rig\n"
        "from twin.rigs.camera_config import available_cameras, load_camera_config\n"
        "from twin.materials import available_materials, load_material\n"
        "from twin.components import RGB_CAMERA_RESPONSES, esser_reflectances\n"
        "from hwbridge.replay import load_mapping\n"
        "from recon.measured_data import read_llanos2019_multispectral, read_spectra_csv\n"
        "from recon.llanos_capture import read_llanos2019_chart_capture\n"
        "from recon.llanos_capture import read_llanos2019_chart_spectra\n"
        "from recon.spectra import DEFAULT_GRID\n"
        "from twin.rigs.bench_config import available_benches, load_bench\n"
        "[load_bench(n).require_files() for n in available_benches()]\n"
        "load_camera_config('flea3_fl3_ge_50s5c').quantum_efficiency.curve(DEFAULT_GRID)\n"
        "[load_rig(n) for n in available_rigs()]\n"
        "[load_camera_config(n) for n in available_cameras()]\n"
        "assert load_camera_config('basler_ccd12').emva1288.descriptor_path().is_file()\n"
        "[load_material(n) for n in available_materials()]\n"
        "[response() for response in RGB_CAMERA_RESPONSES.values()]\n"
        "esser_reflectances(DEFAULT_GRID)\n"
        "for lamp in ('tungsten_lab', 'fluorescent_office'):\n"
        "    read_spectra_csv(f'spectra/lights/{lamp}.csv')\n"
        "load_mapping('llanos2019')\n"
        "read_llanos2019_multispectral()\n"
        "read_llanos2019_chart_capture(); read_llanos2019_chart_spectra()\n"
        "print(json.dumps({m.__name__: m.__file__ for m in (twin, recon, scenes, hwbridge)}))\n"
        "print(json.dumps([available_rigs(), available_cameras(), available_materials(), "
        "available_benches()]))\n"
    )
    environment = {**os.environ, "PYTHONPATH": str(target)}
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, env=environment
    )
    assert result.returncode == 0, result.stderr[-2000:]
    locations, names = (json.loads(line) for line in result.stdout.splitlines()[-2:])
    assert all(path.startswith(str(target)) for path in locations.values())
    assert names == [
        ["dome", "gonio"],
        ["basler_ccd12", "coolsnap_k4", "dslr_nikon_5100", "flea3_fl3_ge_50s5c", "svs_vistek_4022"],
        ["colorchecker16", "lego", "red_fabric", "wallpaper"],
        ["llanos2019"],
    ]
    command = subprocess.run(
        [sys.executable, "-c", "from twin.cli.app import app; app()", "estimate", "dome", "--json"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=environment,
    )
    assert command.returncode == 0, command.stderr[-2000:]
    assert '"leds": 198' in command.stdout
