#!/usr/bin/env bash
# Idempotent set-up of a fresh Debian machine for spectwin:
#   1. a virtual environment in .venv with spectwin and its dev extra installed (editable),
#   2. a system LLVM >= 16 for Mitsuba's llvm_* variants (Dr.Jit 1.5 crashes with LLVM 14/15),
#   3. Debian's chromium and chromium-driver for the browser check of the demo's report.
# Where apt is unavailable the project falls back to the scalar_spectral variant (twin/variant.py)
# and this script prints a warning instead of failing.
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
VENV=.venv
STAMP="$VENV/.spectwin-installed"

if [ ! -x "$VENV/bin/python" ]; then
    echo "bootstrap: creating $VENV with $($PYTHON --version)"
    "$PYTHON" -m venv "$VENV"
fi
# Re-install only when the dependency list changed since the last successful install.
if [ ! -f "$STAMP" ] || [ pyproject.toml -nt "$STAMP" ]; then
    echo "bootstrap: installing spectwin[dev] into $VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet -e ".[dev]"
    # colour-checker-detection pulls in opencv-python, whose cv2 (which needs libGL) may
    # overwrite opencv-python-headless's in the same folder: remove it, restore the headless one.
    "$VENV/bin/python" -m pip uninstall --quiet --yes opencv-python
    "$VENV/bin/python" -m pip install --quiet --force-reinstall --no-deps opencv-python-headless
    touch "$STAMP"
fi

llvm_major() {
    # Prints the LLVM major version Dr.Jit loads, or 0 when it finds none.
    "$VENV/bin/python" - <<'PY' 2>/dev/null || echo 0
import drjit as dr
print(dr.detail.llvm_version()[0] if dr.has_backend(dr.JitBackend.LLVM) else 0)
PY
}

major=$(llvm_major)
if [ "$major" -lt 16 ]; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        echo "bootstrap: Dr.Jit finds LLVM $major (< 16); installing libllvm19 with apt"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq
        apt-get install -y -qq libllvm19 >/dev/null
        major=$(llvm_major)
    fi
fi
# Debian's Chromium and its driver, for the test that opens the demo's HTML report in a browser.
if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        echo "bootstrap: installing chromium and chromium-driver with apt"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq
        apt-get install -y -qq chromium chromium-driver >/dev/null
    else
        echo "bootstrap: no chromium (needs apt as root): the browser check of the report is skipped"
    fi
fi
if [ "$major" -lt 16 ]; then
    echo "bootstrap: WARNING: no LLVM >= 16 available (found $major): spectwin will use the" \
         "slower scalar_spectral Mitsuba variant" >&2
else
    echo "bootstrap: Dr.Jit uses LLVM $major"
fi
