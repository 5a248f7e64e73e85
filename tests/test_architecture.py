"""The architecture's rules (ARCHITECTURE.md): import-linter contracts, import chains, names.

The contracts live in ``pyproject.toml`` (``[tool.importlinter]``); ``lint-imports`` checks
them statically. A copy of the tree with one forbidden import shows that the check can fail.
"""

import ast
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("twin", "recon", "hwbridge")
RENDERER_FREE = ("recon", "hwbridge")
FORBIDDEN = {"twin", "mitsuba", "drjit"}
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def _lint_imports(root: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(LINT_IMPORTS), "--no-cache"], capture_output=True, text=True, cwd=root, check=False
    )


def _copy_of_the_tree(destination: Path) -> Path:
    shutil.copy(ROOT / "pyproject.toml", destination)
    for package in PACKAGES:
        shutil.copytree(
            ROOT / package, destination / package, ignore=shutil.ignore_patterns("data", "*.pyc")
        )
    return destination


def test_every_import_linter_contract_is_kept():
    result = _lint_imports(ROOT)
    assert result.returncode == 0, result.stdout[-3000:]
    assert "0 broken" in result.stdout and "broken" not in result.stdout.split("Contracts:")[0]


def test_a_recon_module_importing_twin_breaks_the_contract(tmp_path):
    tree = _copy_of_the_tree(tmp_path)
    offender = tree / "recon" / "metrics.py"
    offender.write_text(offender.read_text() + "\nfrom twin.render.variant import activate\n")
    result = _lint_imports(tree)
    assert result.returncode == 1
    assert "recon and hwbridge run without a renderer: no twin, mitsuba or drjit BROKEN" in (
        " ".join(result.stdout.split())
    )
    assert "recon.metrics -> twin.render.variant" in result.stdout


def test_a_lower_twin_stage_importing_a_higher_one_breaks_the_layers(tmp_path):
    tree = _copy_of_the_tree(tmp_path)
    offender = tree / "twin" / "materials" / "geometry.py"
    offender.write_text(offender.read_text() + "\nfrom twin.gonio.capture import CAMERA_ID\n")
    result = _lint_imports(tree)
    assert result.returncode == 1
    assert "twin.materials.geometry -> twin.gonio.capture" in result.stdout


RECON_LAYERS = (
    "recon's rooms in layers, each placed: the dome's processing over the BTF store over "
    "calibration, experiments over spectralization, the spectral core at the bottom"
)
HWBRIDGE_LAYERS = (
    "hwbridge's modules in layers, each placed: sessions, replay and device checks over the "
    "devices file, over the drivers, over the store, over plans, targets and layouts, over the "
    "metadata models, over the protocols"
)


@pytest.mark.parametrize(
    ("offender", "line", "contract"),
    [
        (
            "recon/calibration/gonio.py",
            "import hwbridge.session",
            "recon reads capture stores: of hwbridge it imports the store, its metadata models, "
            "its integrity checks and local file store, the dome's store layout and "
            "(recon.errors) the errors, nothing else",
        ),
        ("hwbridge/store.py", "import hwbridge.drivers", HWBRIDGE_LAYERS),
        ("recon/emva/fit.py", "import recon.dome", RECON_LAYERS),
        (
            "twin/validate/figure46.py",
            "import drjit",
            "mitsuba and drjit are imported by twin.render alone (its modules and plugins)",
        ),
    ],
)
def test_an_import_across_a_boundary_breaks_its_contract(tmp_path, offender, line, contract):
    tree = _copy_of_the_tree(tmp_path)
    path = tree / offender
    path.write_text(path.read_text() + f"\n{line}\n")
    result = _lint_imports(tree)
    assert result.returncode == 1
    report = " ".join(result.stdout.split())
    assert f"{contract} BROKEN" in report
    assert " kept, 1 broken." in report


@pytest.mark.parametrize(
    ("package", "contract"), [("recon", RECON_LAYERS), ("hwbridge", HWBRIDGE_LAYERS)]
)
def test_a_module_outside_the_layers_breaks_the_exhaustive_contract(tmp_path, package, contract):
    tree = _copy_of_the_tree(tmp_path)
    (tree / package / "unplaced.py").write_text('"""A module no layer names."""\n')
    result = _lint_imports(tree)
    assert result.returncode == 1
    report = " ".join(result.stdout.split())
    assert f"{contract} BROKEN" in report
    assert f"- {package}.unplaced" in result.stdout


def test_the_longest_import_chain_in_twin_has_at_most_12_modules():
    """The command line reaches a rig's pipeline through the rig registry (``twin.kinds``):
    command, registry, kind, then the rig's own stages."""
    spec = importlib.util.spec_from_file_location(
        "import_chains", ROOT / "scripts" / "import_chains.py"
    )
    chains = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(chains)
    chain = chains.longest_chain("twin")
    assert 2 <= len(chain) <= 12, " -> ".join(chain)


def _private_names_imported(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] in PACKAGES:
                found += [f"{node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
    return found


def test_no_private_name_is_imported_across_modules():
    offenders = {
        str(path.relative_to(ROOT)): _private_names_imported(path)
        for folder in (*PACKAGES, "tests", "benchmarks")
        for path in (ROOT / folder).rglob("*.py")
    }
    assert {path: names for path, names in offenders.items() if names} == {}


def test_the_private_name_check_catches_one(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("from recon.radiometric.hdr import _weights, merge_hdr\n")
    assert _private_names_imported(module) == ["recon.radiometric.hdr._weights"]


def test_importing_every_renderer_free_module_loads_no_renderer():
    """The dynamic side of the first contract: lazy imports included, nothing loads Mitsuba."""
    modules = [
        ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for package in RENDERER_FREE
        for path in (ROOT / package).rglob("*.py")
    ]
    code = (
        "import importlib, sys\n"
        f"for name in {modules!r}:\n"
        "    module = importlib.import_module(name)\n"
        "    for attribute in getattr(module, '__all__', []): getattr(module, attribute)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {sorted(FORBIDDEN)!r}))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout.strip() == "[]"
    assert len(modules) >= 40


@pytest.mark.parametrize(
    "package", ["twin.rigs", "twin.components", "twin.sensor", "twin.materials"]
)
def test_renderer_free_rooms_of_twin_load_no_renderer(package):
    code = (
        "import importlib, pkgutil, sys\n"
        f"root = importlib.import_module({package!r})\n"
        "for info in pkgutil.walk_packages(root.__path__, root.__name__ + '.'):\n"
        "    importlib.import_module(info.name)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('mitsuba', 'drjit')))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout.strip() == "[]"


def _top_level_imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_tests_of_recon_and_hwbridge_run_without_a_renderer():
    """Tests that need Mitsuba or the twin live in tests/integration, not beside recon's."""
    offenders = {
        str(path.relative_to(ROOT)): sorted(_top_level_imports(path) & FORBIDDEN)
        for package in RENDERER_FREE
        for path in (ROOT / "tests" / package).rglob("*.py")
    }
    assert {path: names for path, names in offenders.items() if names} == {}
    assert len(offenders) >= 20


def test_every_name_a_package_re_exports_resolves():
    """Lazy re-exports fail only when used: import every package and read its ``__all__``."""
    code = (
        "import importlib, pkgutil\n"
        "missing = []\n"
        f"for root in {PACKAGES!r}:\n"
        "    package = importlib.import_module(root)\n"
        "    for info in pkgutil.walk_packages(package.__path__, root + '.'):\n"
        "        if not info.ispkg: continue\n"
        "        module = importlib.import_module(info.name)\n"
        "        for name in getattr(module, '__all__', []):\n"
        "            try: getattr(module, name)\n"
        "            except (AttributeError, ImportError): missing.append(info.name + '.' + name)\n"
        "print(missing)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout.strip() == "[]"
