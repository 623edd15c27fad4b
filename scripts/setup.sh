#!/usr/bin/env bash
# Set up the main environment: Debian's DOLFINx (python3-dolfinx-real, NumPy 1.x) plus this
# package installed editable into .venv (a venv on /usr/bin/python3 that sees the system packages).
# Idempotent, non-interactive; run as root (or as a user with sudo). Safe to call from any cwd.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "setup.sh: needs root (or sudo) to install Debian packages" >&2; exit 1
    fi
fi

# the gmsh wheel (test extra) links X11/OpenGL libraries: libglu1-mesa libgl1 libopengl0 libxrender1
# libxcursor1 libxfixes3 libxext6 libxft2 libfontconfig1 libxinerama1 libx11-6 libgomp1
GMSH_LIBS="libglu1-mesa libgl1 libopengl0 libxrender1 libxcursor1 libxfixes3 libxext6 libxft2 libfontconfig1 libxinerama1 libx11-6 libgomp1"
echo "==> apt: python3-dolfinx-real python3-venv libopenblas0 $GMSH_LIBS"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
    python3-dolfinx-real python3-venv libopenblas0 $GMSH_LIBS

SYSPY=/usr/bin/python3
VENV="$ROOT/.venv"

# Recreate the venv if it is missing or broken (made by another interpreter, or without the system
# site packages: DOLFINx and petsc4py would be missing from it and the check below would fail).
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import sys; sys.exit(0 if sys.base_prefix == '/usr' else 1)" 2>/dev/null \
        && grep -qx "include-system-site-packages = true" "$VENV/pyvenv.cfg" 2>/dev/null; then
    echo "==> reusing $VENV"
else
    echo "==> creating $VENV (system site packages)"
    rm -rf "$VENV"
    "$SYSPY" -m venv --system-site-packages "$VENV"
fi

# Pin pip to the exact NumPy/SciPy that Debian's DOLFINx/petsc4py were built against, on top of
# constraints.txt (numpy<2), so that pip never shadows them with a PyPI wheel.
PINS="$VENV/debian-pins.txt"
"$SYSPY" - > "$PINS" <<'PY'
import numpy, scipy
print(f"numpy=={numpy.__version__}")
print(f"scipy=={scipy.__version__}")
PY

echo "==> pip install -e .[test] (constraints: constraints.txt, $(tr '\n' ' ' < "$PINS"))"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
# editable_mode=compat: the project root on sys.path through a .pth line, as a regular install
# behaves at start-up (setuptools' default editable finder costs every process ~15 ms)
"$VENV/bin/python" -m pip install -q -c constraints.txt -c "$PINS" --config-settings editable_mode=compat -e ".[test]"

echo "==> check"
"$VENV/bin/python" - <<'PY'
import numpy, scipy, dolfinx, petsc4py, meshio, matplotlib
import gmsh    # the test extra; its wheel needs the X11/OpenGL libraries installed above
assert numpy.__version__.startswith("1."), numpy.__version__
print(f"numpy {numpy.__version__}  scipy {scipy.__version__}  dolfinx {dolfinx.__version__}  "
      f"petsc4py {petsc4py.__version__}  meshio {meshio.__version__}  matplotlib {matplotlib.__version__}")
PY
echo "==> core-se3 warmup (compiles the numba kernels once into their cache: ~25-70 s)"
"$VENV/bin/python" -m core_se3 warmup
echo "==> setup done: $VENV"
