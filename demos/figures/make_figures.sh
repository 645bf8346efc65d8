#!/usr/bin/env bash
# The charts and pictures of demos/figures/, made by the command line alone
# (run, sweep, plot, render) from demo runs whose results go to a temporary folder.
# About 2 minutes on 2 cores.  PYTHON overrides the interpreter (default: .venv's).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
PYTHON="${PYTHON:-$ROOT/.venv/bin/python}"
FIG=demos/figures
OUT="$(mktemp -d "${TMPDIR:-/tmp}/dolfinx_friction-figures.XXXXXX")"
trap 'rm -rf "$OUT"' EXIT
df() { "$PYTHON" -m dolfinx_friction "$@"; }

# the default scene: history chart and pictures from its files
df run demos/sliding_block.toml --out "$OUT/sliding_block" --quiet
df plot "$OUT/sliding_block" -o "$FIG/sliding_block_history.png"
df render "$OUT/sliding_block" --warp 50 --amplify deformation \
    -o "$FIG/sliding_block_pressure.png"
df render "$OUT/sliding_block" --increment 1 --scalar status --warp 50 --amplify deformation \
    -o "$FIG/sliding_block_status_press.png"

# a friction sweep of the incline: the push force against mu
df sweep demos/incline.toml --set contact.0.mu=0.1,0.2,0.3,0.4,0.5 -j 2 \
    --out "$OUT/incline_sweep" --quiet
cp "$OUT/incline_sweep/sweep.csv" "$FIG/incline_mu_sweep.csv"
df plot "$OUT/incline_sweep" -o "$FIG/incline_mu_sweep.png"
df plot "$OUT/incline_sweep/contact.0.mu=0.3" -o "$FIG/incline_mu0.3_history.png"
df render "$OUT/incline_sweep/contact.0.mu=0.3" --warp 5 --scalar status \
    -o "$FIG/incline_mu0.3_status.png"

# an axisymmetric Neo-Hookean O-ring squeezed by 30 %: the section by von Mises stress
df run demos/o_ring.toml --out "$OUT/o_ring" --quiet
df render "$OUT/o_ring" --von-mises -o "$FIG/o_ring_von_mises.png"

# a rigid wheel rolling freely, then driven with creep: forces and moment, the stick zone at
# the leading edge of the contact
df run demos/rolling_cylinder.toml --out "$OUT/rolling_cylinder" --quiet
df plot "$OUT/rolling_cylinder" -o "$FIG/rolling_cylinder_history.png"
df render "$OUT/rolling_cylinder" --scalar status --warp 20 \
    -o "$FIG/rolling_cylinder_status.png"
