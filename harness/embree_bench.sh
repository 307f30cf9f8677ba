#!/usr/bin/env bash
# ptui's BVH against Embree 4 (embreex from PyPI) on the same triangles and rays (issue 38):
# `cargo xtask embree-workloads` writes the workloads and ptui's figures, then Embree runs on them.
# Makes its own virtual environment (EMBREE_VENV, default target/embree-venv).
#   harness/embree_bench.sh [DIR] [--skip-1m]     # DIR default target/embree-workloads
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="${1:-$root/target/embree-workloads}"
shift || true
venv="${EMBREE_VENV:-$root/target/embree-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q -r "$root/harness/embree_requirements.txt"
(cd "$root" && cargo xtask embree-workloads "$dir" "$@")
exec "$venv/bin/python" "$root/harness/embree_bench.py" "$dir"
