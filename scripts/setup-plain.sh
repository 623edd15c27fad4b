#!/usr/bin/env bash
# Set up a DOLFINx-free environment .venv-np2 from the default `python3` on PATH (NumPy 2 from PyPI),
# used to run the `core` tests (CORE_ONLY=1 pytest -m core). Idempotent; safe to call from any cwd.
# Override the interpreter with PYTHON=/path/to/python3.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

PY="${PYTHON:-python3}"
VENV="$ROOT/.venv-np2"

if ! "$PY" -c "import venv, ensurepip" >/dev/null 2>&1; then
    # Debian's python3 needs python3-venv for venv/ensurepip.
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends python3-venv
fi

# reuse a working venv of Python >= 3.10 (pyproject's requires-python; one of an older Python, e.g.
# made with PYTHON=python3.9, is recreated with $PY instead of failing in pip below)
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import sys; sys.exit(sys.version_info < (3, 10))" 2>/dev/null; then
    echo "==> reusing $VENV"
else
    echo "==> creating $VENV with $("$PY" -c 'import sys; print(sys.executable, sys.version.split()[0])')"
    rm -rf "$VENV"
    "$PY" -m venv "$VENV"
fi

echo "==> pip install -e .[test] (NumPy 2)"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
# editable_mode=compat: a .pth path line instead of setuptools' editable finder (scripts/setup.sh)
"$VENV/bin/python" -m pip install -q "numpy>=2" --config-settings editable_mode=compat -e ".[test]"

"$VENV/bin/python" -c "import numpy, scipy, meshio, matplotlib; print('numpy', numpy.__version__, ' scipy', scipy.__version__)"
echo "==> core-se3 warmup (compiles the numba kernels once into their cache: ~25-70 s)"
"$VENV/bin/python" -m core_se3 warmup
echo "==> setup-plain done: $VENV"
