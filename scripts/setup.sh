#!/usr/bin/env bash
# Set up everything dolfinx_friction needs on a Debian 12 machine:
#   1. Debian packages (DOLFINx 0.5.2, Gmsh, SciPy, pytest, Open MPI, CalculIX, ...),
#   2. a venv at <repo>/.venv on top of Debian's Python (--system-site-packages),
#   3. the package itself (editable) and pyvista from PyPI, with numpy & co.
#      pinned to Debian's versions through scripts/constraints.txt.
#
# Idempotent: when everything is already in place it only checks and returns
# (a fraction of a second). Re-runs pip only when pyproject.toml,
# scripts/constraints.txt or this script change, or the venv looks broken.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

VENV="$ROOT/.venv"
CONSTRAINTS="$ROOT/scripts/constraints.txt"
STAMP="$VENV/.dolfinx_friction-setup.stamp"
SYS_PY=/usr/bin/python3
EXPECTED_NUMPY=1.24.2

DEB_PACKAGES=(
    python3-dolfinx python3-gmsh python3-scipy python3-pytest python3-venv
    python3-setuptools python3-pip libegl1 calculix-ccx python3-numba
    python3-matplotlib python3-hypothesis python3-tqdm openmpi-bin
    python3-sphinx python3-myst-parser  # the API reference (docs/), built by scripts/test.sh
    libopenblas0-serial  # optimised BLAS for MUMPS: ~7x faster factorisations than netlib
)

say() { printf 'setup.sh: %s\n' "$*"; }
die() { printf 'setup.sh: ERROR: %s\n' "$*" >&2; exit 1; }

LOG="$(mktemp "${TMPDIR:-/tmp}/dolfinx_friction-setup.XXXXXX.log")"
trap 'rm -f "$LOG"' EXIT

# run_quiet "what" cmd...: run cmd with its output in $LOG; on failure show the
# end of the log and stop.
run_quiet() {
    local what="$1"; shift
    if ! "$@" >"$LOG" 2>&1; then
        printf 'setup.sh: ERROR: %s failed: %s\n' "$what" "$*" >&2
        printf -- '----- last lines of output -----\n' >&2
        tail -n 40 "$LOG" >&2
        printf -- '--------------------------------\n' >&2
        exit 1
    fi
}

# ---------------------------------------------------------------- Debian packages
command -v dpkg >/dev/null 2>&1 || die "dpkg not found: this script is for Debian 12 (bookworm)."

missing=()
for pkg in "${DEB_PACKAGES[@]}"; do
    status="$(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null || true)"
    [[ "$status" == installed ]] || missing+=("$pkg")
done

if ((${#missing[@]})); then
    if [[ "$(id -u)" -eq 0 ]]; then
        SUDO=()
    elif command -v sudo >/dev/null 2>&1; then
        SUDO=(sudo)
    else
        die "missing Debian packages (${missing[*]}) and not root, and sudo is not available."
    fi
    say "installing Debian packages: ${missing[*]} (this takes a few minutes)"
    export DEBIAN_FRONTEND=noninteractive
    run_quiet "apt-get update" "${SUDO[@]}" apt-get update -q
    run_quiet "apt-get install" "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q "${missing[@]}"
fi

[[ -x "$SYS_PY" ]] || die "$SYS_PY not found after installing the Debian packages."

# ---------------------------------------------------------------- venv
# Keep the venv away from any user site-packages and pyenv settings.
export PYTHONNOUSERSITE=1
unset PYTHONHOME PYTHONPATH VIRTUAL_ENV || true

venv_ok() {
    [[ -x "$VENV/bin/python" && -f "$VENV/pyvenv.cfg" ]] || return 1
    grep -Eq '^include-system-site-packages *= *true' "$VENV/pyvenv.cfg" || return 1
    grep -Eq '^home *= */usr/bin$' "$VENV/pyvenv.cfg" || return 1
    "$VENV/bin/python" -c 'import sys' >/dev/null 2>&1 || return 1
}

if [[ -e "$VENV" ]] && ! venv_ok; then
    say "existing .venv is not a --system-site-packages venv of $SYS_PY (or is broken): recreating it"
    rm -rf "$VENV"
fi
if [[ ! -e "$VENV" ]]; then
    say "creating .venv"
    run_quiet "creating the venv" "$SYS_PY" -m venv --system-site-packages "$VENV"
fi

# ---------------------------------------------------------------- pip installs
want_stamp="$(cat "$ROOT/pyproject.toml" "$CONSTRAINTS" "${BASH_SOURCE[0]}" | sha256sum | cut -d' ' -f1)"

# Cheap check that the venv still holds what we installed (no imports of the
# heavy packages here: metadata only).
installed_ok() {
    [[ -x "$VENV/bin/dolfinx-friction" ]] || return 1
    "$VENV/bin/python" - "$EXPECTED_NUMPY" <<'EOF' >/dev/null 2>&1
import sys
import importlib.metadata as md
assert md.version("numpy") == sys.argv[1]
md.version("pyvista")
md.version("vtk")
md.version("dolfinx_friction")
EOF
}

if [[ -f "$STAMP" && "$(cat "$STAMP")" == "$want_stamp" ]] && installed_ok; then
    exit 0
fi

if [[ -f "$STAMP" ]] && ! installed_ok; then
    # Something changed the venv behind our back (e.g. pip pulled numpy 2):
    # start from a clean venv so Debian's packages show through again.
    say ".venv no longer matches the requirements: recreating it"
    rm -rf "$VENV"
    run_quiet "creating the venv" "$SYS_PY" -m venv --system-site-packages "$VENV"
fi
rm -f "$STAMP"

PIP=("$VENV/bin/python" -m pip --disable-pip-version-check --no-input -q)

say "installing dolfinx_friction (editable) and pyvista into .venv"
run_quiet "pip install -e ." "${PIP[@]}" install --no-build-isolation --no-deps -e "$ROOT"
run_quiet "pip install pyvista" "${PIP[@]}" install -c "$CONSTRAINTS" pyvista

# Full check: the stack imports together and numpy is still Debian's.
if ! numpy_version="$("$VENV/bin/python" -c \
        "import numpy, dolfinx, petsc4py, scipy, pyvista; print(numpy.__version__)" 2>"$LOG")"; then
    cat "$LOG" >&2
    die "the installed environment does not import (numpy, dolfinx, petsc4py, scipy, pyvista)."
fi
[[ "$numpy_version" == "$EXPECTED_NUMPY" ]] \
    || die "numpy in .venv is $numpy_version, expected Debian's $EXPECTED_NUMPY (check scripts/constraints.txt)."

printf '%s\n' "$want_stamp" >"$STAMP"
say "environment ready (.venv, numpy $numpy_version)"
