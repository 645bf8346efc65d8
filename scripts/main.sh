#!/usr/bin/env bash
# Set everything up (scripts/setup.sh), then run the bundled default scene.
# Extra arguments go to `dolfinx-friction run`.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

bash scripts/setup.sh

export PYTHONNOUSERSITE=1
# Render with EGL directly (no X server): avoids VTK's "bad X server" warning.
export VTK_DEFAULT_OPENGL_WINDOW="${VTK_DEFAULT_OPENGL_WINDOW:-vtkEGLRenderWindow}"

exec .venv/bin/dolfinx-friction run demos/sliding_block.toml "$@"
