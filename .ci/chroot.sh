#!/usr/bin/env bash
# Run dolfinx_friction's test suite on a newer Debian from a Debian 12 host, inside a
# root filesystem of that suite:
#   trixie  Debian 13: dolfinx 0.9, Python 3.13, numpy 2, PETSc 3.22 (no calculix-ccx);
#   sid     Debian unstable: dolfinx 0.11, Python 3.14, numpy 2.4, PETSc 3.25, ccx 2.23
#           (its Release file may be past its validity date: apt is told to accept it).
#
#   bash .ci/chroot.sh SUITE                  # build-or-reuse the rootfs, run everything
#   bash .ci/chroot.sh SUITE --build-only     # only make sure the cached rootfs exists
#   bash .ci/chroot.sh SUITE --rebuild        # rebuild the cached rootfs first
#   bash .ci/chroot.sh SUITE -- -k gmsh -x    # extra arguments after -- go to pytest
#
# Stages (each prints how long it took):
#   1. rootfs: a tarball cached OUTSIDE the repository
#      ($DOLFINX_FRICTION_ROOTFS_CACHE, default /var/cache/dolfinx_friction/
#      SUITE-rootfs.tar), built with mmdebstrap (installed with apt-get when missing)
#      from the Debian mirror this machine's apt sources use (it stops with one line when
#      they name none: no fallback address); rebuilt when the package list below changes
#      (a stamp file next to it).
#   2. unpack it into a temporary directory of its own, copy the working tree in (no
#      .git, .venv, caches or results), bind-mount /proc, /sys, /dev, /dev/pts, /dev/shm;
#      a trap unmounts them and removes the directory on any exit.
#   3. pytest without MPI (the whole suite, in two worker processes: pytest-xdist),
#      then under `mpirun -n 2` (the suite's MPI_TESTS, below), as root inside the chroot, with PYTHONPATH at
#      the copied repo (Debian's packages, no venv).
#   4. the release check: .ci/release_check/scene.toml (a block pressed onto a
#      foundation and slid with Coulomb friction; mesh from make_mesh.py, written
#      once on the host) run with `python3 -m dolfinx_friction run` on the host
#      (Debian 12, dolfinx 0.5) and in the chroot, serially and on 2 ranks: every
#      reaction component of each chroot history.csv must agree with the host's
#      within 1e-6 relative (.ci/compare_histories.py).  The scene is also
#      rendered once in the chroot under xvfb-run (.ci/release_check/render.py): the
#      pyvista path is in no test.
#
# Exits non-zero if any stage fails, or if a pytest run collects no tests
# (pytest exit 5).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SUITE="${1:-}"
case "$SUITE" in
    trixie|sid) shift ;;
    *) printf 'chroot.sh: ERROR: the first argument is the suite: trixie or sid (got "%s")\n' \
           "$SUITE" >&2; exit 2 ;;
esac
CACHE_DIR="${DOLFINX_FRICTION_ROOTFS_CACHE:-/var/cache/dolfinx_friction}"
TARBALL="$CACHE_DIR/$SUITE-rootfs.tar"
STAMP="$TARBALL.stamp"
# dolfinx's JIT cache (compiled forms) kept between runs; emptied with each new rootfs
JIT_CACHE="$CACHE_DIR/$SUITE-xdg-cache"
HOST_PY="${HOST_PYTHON:-/usr/bin/python3}"
# Relative tolerance on the reactions of the release-check scene (stage 4).
COMPARE_RTOL="${COMPARE_RTOL:-1e-6}"

PACKAGES=(
    python3-dolfinx python3-gmsh python3-scipy python3-pytest python3-hypothesis
    python3-pyvista python3-matplotlib python3-numba python3-tqdm libegl1 openmpi-bin
    # the serial run in two processes (pytest -n 2): 408 s instead of 577-688 on sid
    python3-pytest-xdist
    # an optimised BLAS for MUMPS (the host's scripts/setup.sh installs it too): without
    # it the reference BLAS serves, and a 3D P2 Hertz run took 178 s of CPU, not 24
    libopenblas0-serial
    # VTK renders through X only in these suites: pictures need a virtual X server
    xvfb xauth
    # dolfinx JIT-compiles forms (ffcx -> cffi -> C compiler + Python headers)
    build-essential python3-dev
)
APT_OPTIONS=('APT::Install-Recommends "false"')
# The tests run on 2 ranks in the chroot: those whose code has a parallel path of its own
# (the building block and solvers, the verification scenes, the result files written by
# ranks together).  The whole suite runs on 2 ranks on the host; here the MPI run checks what
# differs with the release (dolfinx's parallel layouts, Open MPI 5).
MPI_TESTS=(tests/fem tests/verification tests/cli/test_outputs.py)
# Every demo on 1, 2 and 3 ranks (tests/cli/test_ranks.py, its own mpirun jobs): on the
# host only, where the whole suite runs on 2 ranks as well; the chroots' serial runs
# leave it out (a third of their time).
SERIAL_SKIP=(--deselect tests/cli/test_ranks.py::test_ranks_match_serial)
case "$SUITE" in
    trixie)
        # what 0.9 does not share with 0.11 is a few branches of the compat module (mesh
        # creation, vectors, geometry maps), which tests/fem runs on 2 ranks; the
        # verification scenes on 2 ranks run the same package code on top of them and add
        # no information past sid's
        MPI_TESTS=(tests/fem tests/cli/test_outputs.py)
        DESCRIPTION="Debian 13 (dolfinx 0.9)" ;;  # trixie has no calculix-ccx: the peer tests skip
    sid)
        DESCRIPTION="Debian sid (dolfinx 0.11)"
        PACKAGES+=(calculix-ccx)  # 2.23: the CalculiX peer tests run against it
        APT_OPTIONS+=('Acquire::Check-Valid-Until "false"') ;;
esac

say() { printf 'chroot.sh (%s): %s\n' "$SUITE" "$*"; }
die() { printf 'chroot.sh (%s): ERROR: %s\n' "$SUITE" "$*" >&2; exit 1; }
now() { date +%s; }
took() { say "$1 took $(($(now) - $2)) s"; }

build_only=0
rebuild=0
PYTEST_ARGS=()
while (($#)); do
    case "$1" in
        --build-only) build_only=1 ;;
        --rebuild) rebuild=1 ;;
        --) shift; PYTEST_ARGS=("$@"); break ;;
        -h|--help) sed -n '2,37p' "${BASH_SOURCE[0]}"; exit 0 ;;
        *) die "unknown argument: $1 (pytest arguments go after --)" ;;
    esac
    shift
done

[[ "$(id -u)" -eq 0 ]] || die "needs root (chroot, bind mounts, mmdebstrap in root mode)"

# ------------------------------------------------------------------ stage 1: rootfs
# The Debian mirror of this machine's apt configuration: the URI of the binary
# source that serves this machine's own suite (VERSION_CODENAME of /etc/os-release)
# with component main, as apt itself reads its sources (one-line sources.list and
# deb822 .sources alike, disabled entries skipped).  Prints nothing when there is
# none: there is no fallback address.
debian_mirror() {
    local codename
    codename="$(. /etc/os-release 2>/dev/null && printf '%s' "${VERSION_CODENAME:-}")" || true
    [[ -n "$codename" ]] || return 0
    { apt-get indextargets --no-release-info \
          --format '$(TARGET_OF) $(RELEASE) $(COMPONENT) $(REPO_URI)' 2>/dev/null || true; } \
        | awk -v suite="$codename" '
            !found && $1 == "deb" && $2 == suite && $3 == "main" && $4 ~ /^[a-z+]+:\/\// {
                sub(/\/$/, "", $4); print $4; found = 1 }'
}

want_stamp="$(printf '%s\n' "$SUITE" "${PACKAGES[@]}" "${APT_OPTIONS[@]}" | sha256sum | cut -d' ' -f1)"

build_rootfs() {
    local start mirror tmp
    start="$(now)"
    mkdir -p "$CACHE_DIR"
    # (two suites may be built at once: one of them installs mmdebstrap)
    if ! command -v mmdebstrap >/dev/null 2>&1; then
        say "installing mmdebstrap"
        (
            flock 9
            command -v mmdebstrap >/dev/null 2>&1 \
                || DEBIAN_FRONTEND=noninteractive apt-get install -y -q mmdebstrap >/dev/null \
                || { apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive \
                     apt-get install -y -q mmdebstrap >/dev/null; }
        ) 9>"$CACHE_DIR/.install.lock" || die "cannot install mmdebstrap"
    fi
    mirror="$(debian_mirror)"
    [[ -n "$mirror" ]] || die "no Debian mirror in this machine's apt sources (no 'deb' source" \
        "of suite $(. /etc/os-release 2>/dev/null; echo "${VERSION_CODENAME:-?}") with component" \
        "main in /etc/apt/sources.list or /etc/apt/sources.list.d/): add one, or build elsewhere"
    say "building the $SUITE rootfs from $mirror into $TARBALL (takes a few minutes)"
    tmp="$TARBALL.partial.$$"
    rm -f "$tmp"
    local log="$CACHE_DIR/$SUITE-mmdebstrap.log"
    local aptopts=() opt
    for opt in "${APT_OPTIONS[@]}"; do aptopts+=("--aptopt=$opt"); done
    if ! mmdebstrap --mode=root --variant=apt --format=tar "${aptopts[@]}" \
            --include="$(IFS=,; echo "${PACKAGES[*]}")" \
            "$SUITE" "$tmp" "deb $mirror $SUITE main" >"$log" 2>&1; then
        tail -n 40 "$log" >&2
        rm -f "$tmp"
        die "mmdebstrap failed (log: $log)"
    fi
    mv -f "$tmp" "$TARBALL"
    printf '%s\n' "$want_stamp" >"$STAMP"
    rm -rf "$JIT_CACHE"
    took "building the rootfs ($(du -h "$TARBALL" | cut -f1))" "$start"
}

"$HOST_PY" -c 'import dolfinx, gmsh' 2>/dev/null \
    || die "$HOST_PY cannot import dolfinx and gmsh: set up the host first (bash scripts/setup.sh)"

if ((rebuild)) || [[ ! -f "$TARBALL" || ! -f "$STAMP" || "$(cat "$STAMP")" != "$want_stamp" ]]; then
    build_rootfs
else
    say "reusing the cached rootfs $TARBALL"
fi
((build_only)) && exit 0

# ------------------------------------------------------------------ stage 2: chroot
WORK="$(mktemp -d "${TMPDIR:-/tmp}/dolfinx_friction-$SUITE.XXXXXX")"
R="$WORK/rootfs"
MOUNTS=()

cleanup() {
    local rc=$? i
    for ((i = ${#MOUNTS[@]} - 1; i >= 0; i--)); do
        umount "${MOUNTS[i]}" 2>/dev/null || umount -l "${MOUNTS[i]}" 2>/dev/null \
            || printf 'chroot.sh: WARNING: could not unmount %s\n' "${MOUNTS[i]}" >&2
    done
    # Only remove the tree when nothing is mounted below it any more.
    if ! grep -q " $WORK/" /proc/self/mounts; then
        rm -rf --one-file-system "$WORK"
    else
        printf 'chroot.sh: WARNING: mounts left below %s, not removed\n' "$WORK" >&2
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

start="$(now)"
mkdir -p "$R"
tar -xf "$TARBALL" -C "$R"
for d in proc sys dev dev/pts dev/shm; do
    mkdir -p "$R/$d"
    mount --bind "/$d" "$R/$d"
    MOUNTS+=("$R/$d")
done
mkdir -p "$JIT_CACHE" "$R/work/cache"
mount --bind "$JIT_CACHE" "$R/work/cache"
MOUNTS+=("$R/work/cache")
cp /etc/resolv.conf "$R/etc/resolv.conf" 2>/dev/null || true
grep -q "$(hostname)" "$R/etc/hosts" 2>/dev/null || echo "127.0.1.1 $(hostname)" >>"$R/etc/hosts"

# The working tree (what is being tested, committed or not), without bulky or
# host-specific parts.
mkdir -p "$R/work/repo" "$R/work/home" "$R/work/tmp"
tar -C "$ROOT" -cf - \
    --exclude=./.git --exclude=./.venv --exclude=__pycache__ --exclude=.pytest_cache \
    --exclude=.hypothesis --exclude='*_results' --exclude='*.egg-info' --exclude=./build . \
    | tar -C "$R/work/repo" -xf -
took "unpacking the rootfs and copying the repo" "$start"

# in_chroot CMD...: run a command in the chroot, in the copied repo, with a clean environment.
# (LIMIT: a command prefix, set by `limited` below)
LIMIT=()
in_chroot() {
    "${LIMIT[@]}" chroot "$R" /usr/bin/env -i \
        PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
        HOME=/work/home XDG_CACHE_HOME=/work/cache TMPDIR=/work/tmp \
        LANG=C.UTF-8 PYTHONPATH=/work/repo PYTHONDONTWRITEBYTECODE=1 PYTHONNOUSERSITE=1 \
        OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
        OMPI_MCA_btl=self,sm OMPI_MCA_btl_sm_single_copy_mechanism=none \
        CI="${CI:-}" \
        bash -c 'cd /work/repo && "$@"' in-chroot "$@"
}

in_chroot python3 -c '
import sys, numpy, dolfinx, basix, ufl, petsc4py.PETSc as P, mpi4py, scipy, gmsh
print("chroot.sh: " + sys.argv[1] + ": Python %s, dolfinx %s, basix %s, ufl %s, PETSc %s, numpy %s, scipy %s, gmsh %s"
      % (sys.version.split()[0], dolfinx.__version__, basix.__version__, ufl.__version__,
         ".".join(map(str, P.Sys.getVersion())), numpy.__version__, scipy.__version__,
         gmsh.__version__))
' "$SUITE"

# Each pytest run is stopped after DOLFINX_FRICTION_TEST_TIMEOUT seconds (default 1800): a
# test that fails on one rank only can leave the other rank waiting in a collective.
limited() {
    local LIMIT=(timeout --kill-after=30 "${DOLFINX_FRICTION_TEST_TIMEOUT:-1800}")
    "$@"
}

describe() {  # describe NAME RC
    case "$2" in
        0) say "$1 passed" ;;
        5) printf 'chroot.sh: %s FAILED: no tests were collected (pytest exit 5)\n' "$1" >&2 ;;
        124|137) printf 'chroot.sh: %s FAILED: stopped after its time limit (hung?)\n' "$1" >&2 ;;
        *) printf 'chroot.sh: %s FAILED (exit code %s)\n' "$1" "$2" >&2 ;;
    esac
}

# ------------------------------------------------------------------ stage 3: pytest
targets=(tests)
for arg in "${PYTEST_ARGS[@]}"; do
    [[ "$arg" != -* && -e "$ROOT/${arg%%::*}" ]] && { targets=(); break; }
done

start="$(now)"
say "$SUITE serial run: pytest -q -p no:cacheprovider -n 2 ${targets[*]} ${SERIAL_SKIP[*]} ${PYTEST_ARGS[*]}"
serial_rc=0
limited in_chroot python3 -m pytest -q -p no:cacheprovider -n 2 "${targets[@]}" \
    "${SERIAL_SKIP[@]}" "${PYTEST_ARGS[@]}" || serial_rc=$?
describe "$SUITE serial run" "$serial_rc"
took "$SUITE serial run" "$start"

start="$(now)"
mpi_targets=("${MPI_TESTS[@]}")
((${#targets[@]})) || mpi_targets=()
say "$SUITE MPI run: mpirun -n 2 pytest -q -p no:cacheprovider ${mpi_targets[*]} ${PYTEST_ARGS[*]}"
mpi_rc=0
# Only rank 0 prints; the other rank's output is shown when the run fails.
limited in_chroot mpirun -n 2 --oversubscribe --bind-to none \
    bash -c '
        if [[ "${OMPI_COMM_WORLD_RANK:-0}" == 0 ]]; then
            exec "$@"
        else
            exec "$@" >"/work/tmp/pytest.rank${OMPI_COMM_WORLD_RANK}.log" 2>&1
        fi
    ' rank-wrapper python3 -m pytest -q -p no:cacheprovider --color=no \
    "${mpi_targets[@]}" "${PYTEST_ARGS[@]}" || mpi_rc=$?
if ((mpi_rc != 0)); then
    for f in "$R"/work/tmp/pytest.rank*.log; do
        [[ -e "$f" ]] || continue
        echo "----- output of ${f##*/} -----" >&2
        tail -n 200 "$f" >&2
    done
fi
describe "$SUITE MPI run (2 ranks)" "$mpi_rc"
took "$SUITE MPI run" "$start"

# ------------------------------------------------------------------ stage 4: releases agree
# .ci/release_check/scene.toml on the very same mesh (written once, on the host):
# the suite serially and on `mpirun -n 2` against the host (Debian 12) serial run.
# The host runs the snapshot of the working tree copied into the chroot, so both
# releases run the same code even while the working tree changes.
compare_rc=0
start="$(now)"
say "releases: .ci/release_check/scene.toml on $DESCRIPTION (serial, 2 ranks) and on the host"
SNAP="$R/work/repo"
RC_HOST="$WORK/release_check"
mkdir -p "$RC_HOST" "$R/work/release_check"
cp "$SNAP/.ci/release_check/scene.toml" "$RC_HOST/"
"$HOST_PY" "$SNAP/.ci/release_check/make_mesh.py" "$RC_HOST/blocks.msh" || compare_rc=$?
cp "$RC_HOST/scene.toml" "$RC_HOST/blocks.msh" "$R/work/release_check/" || compare_rc=$?
if ((compare_rc == 0)); then
    (cd "$RC_HOST" && env PYTHONPATH="$SNAP" PYTHONDONTWRITEBYTECODE=1 \
        "$HOST_PY" -m dolfinx_friction run --quiet --out "$RC_HOST/host" "$RC_HOST/scene.toml") \
        || compare_rc=$?
    in_chroot python3 -m dolfinx_friction run --quiet --out /work/release_check/serial \
        /work/release_check/scene.toml || compare_rc=$?
    in_chroot mpirun -n 2 --oversubscribe --bind-to none python3 -m dolfinx_friction run \
        --quiet --out /work/release_check/mpi2 /work/release_check/scene.toml || compare_rc=$?
    # the pyvista path (compat.vtk_mesh) is in no test: render the scene once
    in_chroot xvfb-run -a python3 .ci/release_check/render.py /work/release_check/scene.toml \
        /work/release_check/render || compare_rc=$?
fi
if ((compare_rc == 0)); then
    "$HOST_PY" "$SNAP/.ci/compare_histories.py" --rtol "$COMPARE_RTOL" \
        --label "Debian 12 (dolfinx 0.5)" --label "$DESCRIPTION" \
        "$RC_HOST/host/history.csv" "$R/work/release_check/serial/history.csv" \
        || compare_rc=$?
    "$HOST_PY" "$SNAP/.ci/compare_histories.py" --rtol "$COMPARE_RTOL" --quiet \
        --label "Debian 12 (dolfinx 0.5)" --label "$DESCRIPTION, 2 ranks" \
        "$RC_HOST/host/history.csv" "$R/work/release_check/mpi2/history.csv" \
        || compare_rc=$?
fi
describe "release comparison" "$compare_rc"
took "release comparison" "$start"

if ((serial_rc != 0 || mpi_rc != 0 || compare_rc != 0)); then
    exit 1
fi
say "all $DESCRIPTION runs passed"
