"""Hard rule of ARCHITECTURE.md: recon and hwbridge never import twin, mitsuba or drjit."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"twin", "mitsuba", "drjit"}
RENDERER_FREE = ("recon", "hwbridge")


def _imported_top_level_modules(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", RENDERER_FREE)
def test_renderer_free_packages_have_no_forbidden_import_statements(package):
    offenders = {
        str(path.relative_to(ROOT)): sorted(_imported_top_level_modules(path) & FORBIDDEN)
        for path in (ROOT / package).rglob("*.py")
    }
    assert {path: names for path, names in offenders.items() if names} == {}


def test_importing_every_renderer_free_module_loads_no_renderer():
    modules = [
        ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for package in RENDERER_FREE
        for path in (ROOT / package).rglob("*.py")
    ]
    code = (
        "import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {sorted(FORBIDDEN)!r}))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout.strip() == "[]"
    assert len(modules) >= 5


def test_the_rule_check_catches_a_violation(tmp_path):
    offender = tmp_path / "bad.py"
    offender.write_text("import numpy\nfrom twin.components import HMILamp\nimport drjit as dr\n")
    assert _imported_top_level_modules(offender) & FORBIDDEN == {"twin", "drjit"}
