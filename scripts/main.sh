#!/usr/bin/env bash
# Set everything up (scripts/setup.sh), then run the bundled default scene
# (demos/sliding_block.toml): results and a picture in demos/sliding_block_results/.
# Extra arguments go to the demo script (--quiet, --set KEY=VALUE, --out DIR, ...).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

bash scripts/setup.sh

export PYTHONNOUSERSITE=1
# Render with EGL directly (no X server): avoids VTK's "bad X server" warning.
export VTK_DEFAULT_OPENGL_WINDOW="${VTK_DEFAULT_OPENGL_WINDOW:-vtkEGLRenderWindow}"

exec .venv/bin/python demos/sliding_block.py "$@"
