"""The type checker's verdict on the product: mypy as ``pyproject.toml`` configures it (strict
on ``hwbridge`` and ``recon``, the defaults on ``twin``), caching in ``.mypy_cache``."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_mypy_finds_no_type_errors():
    result = subprocess.run(
        [sys.executable, "-m", "mypy"], capture_output=True, text=True, cwd=ROOT, check=False
    )
    assert result.returncode == 0, (result.stdout + result.stderr)[-6000:]
