#!/usr/bin/env bash
# Mitsuba 3 references for ptui's mesh scenes (harness/mitsuba_mesh.py): the scene's meshes are
# exported by `cargo xtask export-meshes`, the rest translated from the scene file.
#   harness/mitsuba_mesh.sh scenes/torus-knot.toml --spp 256 --passes 128   # tests/refs/torus-knot.exr
#   harness/mitsuba_mesh.sh scenes/spot.toml --spp 256 --passes 128         # tests/refs/spot.exr
#   harness/mitsuba_mesh.sh --help
# The environment (Python >= 3.11, Mitsuba's venv, libLLVM >= 16 for the default llvm_ad_rgb
# variant; `--variant scalar_rgb` needs none): harness/mitsuba_env.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
. "$root/harness/mitsuba_env.sh"
exec "$venv/bin/python" "$root/harness/mitsuba_mesh.py" "$@"
