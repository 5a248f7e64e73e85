"""Figures are built on ``matplotlib.figure.Figure`` objects, never through pyplot's global state.

Importing a study or a validation module (from a notebook, say) must not switch the plotting
backend, and writing a figure must not leave a pyplot figure open. The probe runs in a fresh
interpreter that selects the ``svg`` backend and imports pyplot first, so that a module calling
``matplotlib.use("Agg")`` or ``plt.subplots`` without ``plt.close`` shows up.
"""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FIGURE_PACKAGES = ("twin/studies", "twin/validate")

_PROBE = """
import importlib, json, sys
from pathlib import Path

import matplotlib

matplotlib.use("svg")
import matplotlib.pyplot as plt

before = matplotlib.get_backend()
for name in {modules!r}:
    importlib.import_module(name)
after_imports = matplotlib.get_backend()
{write_figure}
print(json.dumps({{
    "before": before,
    "after_imports": after_imports,
    "after_figure": matplotlib.get_backend(),
    "open_figures": plt.get_fignums(),
}}))
"""


def _probe(modules: list[str], write_figure: str, **kwargs) -> dict:
    code = _PROBE.format(modules=modules, write_figure=write_figure)
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, **kwargs
    )
    return json.loads(result.stdout.strip().splitlines()[-1])


def _figure_modules() -> list[str]:
    return sorted(
        ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for package in FIGURE_PACKAGES
        for path in (ROOT / package).rglob("*.py")
    )


def test_importing_studies_and_validation_keeps_the_backend_and_leaves_no_figure(tmp_path):
    modules = _figure_modules()
    assert {"twin.studies.spectralization", "twin.validate.smoke"} <= set(modules)
    path = tmp_path / "lamps_filter.png"
    state = _probe(
        modules,
        "from twin.studies.demo_report import plot_lamps_and_filter\n"
        f"plot_lamps_and_filter(Path({str(path)!r}))",
        cwd=ROOT,
    )
    assert state == {
        "before": "svg",
        "after_imports": "svg",
        "after_figure": "svg",
        "open_figures": [],
    }
    assert path.read_bytes().startswith(b"\x89PNG")


def test_the_probe_catches_a_module_that_uses_pyplot(tmp_path):
    (tmp_path / "pyplot_study.py").write_text(
        "import matplotlib\n"
        "matplotlib.use('Agg')\n"
        "import matplotlib.pyplot as plt\n"
        "def write(path):\n"
        "    figure, axes = plt.subplots()\n"
        "    figure.savefig(path)\n"
    )
    state = _probe(
        ["pyplot_study"],
        f"import pyplot_study\npyplot_study.write(Path({str(tmp_path / 'out.png')!r}))",
        cwd=tmp_path,
    )
    assert state["after_imports"].lower() == "agg" != state["before"]
    assert state["open_figures"] == [1]
