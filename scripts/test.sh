#!/usr/bin/env bash
# Set everything up (scripts/setup.sh), then run the test suite twice:
# serially, and under `mpirun -n 2`. Extra arguments go to pytest in both runs
# (e.g. `bash scripts/test.sh -k friction -x`); if they name test paths, those
# replace the default `tests` directory.
#
# Then it builds the API reference (docs/, Sphinx) once, warnings as errors.
#
# Exits non-zero if either run fails or collects no tests (pytest exit 5), or if
# the reference has a warning.
# Each run is stopped after DOLFINX_FRICTION_TEST_TIMEOUT seconds (default
# 2400): a test that fails on one rank only can leave the other rank waiting
# in a collective forever.
# Under MPI only rank 0 prints; the other ranks' output goes to a log file that
# is shown when that run fails.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

bash scripts/setup.sh

PY="$ROOT/.venv/bin/python"
export PYTHONNOUSERSITE=1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Containers often forbid the cross-memory-attach syscalls Open MPI's shared
# memory transport tries first; don't let that turn into warnings or failures.
export OMPI_MCA_btl_vader_single_copy_mechanism="${OMPI_MCA_btl_vader_single_copy_mechanism:-none}"
# Render with EGL directly (no X server): avoids VTK's "bad X server" warning.
export VTK_DEFAULT_OPENGL_WINDOW="${VTK_DEFAULT_OPENGL_WINDOW:-vtkEGLRenderWindow}"

TIMEOUT="${DOLFINX_FRICTION_TEST_TIMEOUT:-2400}"
run_limited() { timeout --foreground --kill-after=30 "$TIMEOUT" "$@"; }

# Test location: `tests` unless an extra argument is an existing path.
targets=(tests)
for arg in "$@"; do
    if [[ "$arg" != -* && -e "${arg%%::*}" ]]; then
        targets=()
        break
    fi
done

describe() {  # describe NAME RC
    case "$2" in
        0) echo "test.sh: $1 run passed" ;;
        5) echo "test.sh: $1 run FAILED: no tests were collected (pytest exit 5)" >&2 ;;
        124|137) echo "test.sh: $1 run FAILED: stopped after ${TIMEOUT}s (hung?)" >&2 ;;
        *) echo "test.sh: $1 run FAILED (exit code $2)" >&2 ;;
    esac
}

echo "test.sh: serial run: pytest -q${targets[*]:+ ${targets[*]}}${*:+ $*}"
serial_rc=0
run_limited "$PY" -m pytest -q "${targets[@]}" "$@" || serial_rc=$?
describe serial "$serial_rc"

MPI_LOG_DIR="$(mktemp -d "${TMPDIR:-/tmp}/dolfinx_friction-mpi.XXXXXX")"
trap 'rm -rf "$MPI_LOG_DIR"' EXIT

echo "test.sh: MPI run: mpirun -n 2 pytest -q -p no:cacheprovider${targets[*]:+ ${targets[*]}}${*:+ $*}"
mpi_rc=0
run_limited mpirun -n 2 --oversubscribe --bind-to none \
    -x PYTHONNOUSERSITE -x VTK_DEFAULT_OPENGL_WINDOW \
    bash -c '
        log="$1"; shift
        if [[ "${OMPI_COMM_WORLD_RANK:-0}" == 0 ]]; then
            exec "$@"
        else
            exec "$@" >"$log.rank${OMPI_COMM_WORLD_RANK}" 2>&1
        fi
    ' rank-wrapper "$MPI_LOG_DIR/pytest" \
    "$PY" -m pytest -q -p no:cacheprovider --color=no "${targets[@]}" "$@" || mpi_rc=$?
if ((mpi_rc != 0)); then
    for f in "$MPI_LOG_DIR"/pytest.rank*; do
        [[ -e "$f" ]] || continue
        echo "----- output of ${f##*.} -----" >&2
        tail -n 200 "$f" >&2
    done
fi
describe "MPI (2 ranks)" "$mpi_rc"

DOCS_DIR="$(mktemp -d "${TMPDIR:-/tmp}/dolfinx_friction-docs.XXXXXX")"
trap 'rm -rf "$MPI_LOG_DIR" "$DOCS_DIR"' EXIT
echo "test.sh: API reference: sphinx -W --keep-going -b html docs"
docs_rc=0
"$PY" -m sphinx -W --keep-going -q -b html docs "$DOCS_DIR" || docs_rc=$?
if ((docs_rc == 0)); then
    echo "test.sh: API reference built without warnings"
else
    echo "test.sh: API reference FAILED (warnings or errors above)" >&2
fi

if ((serial_rc != 0 || mpi_rc != 0 || docs_rc != 0)); then
    exit 1
fi
echo "test.sh: all test runs passed"
