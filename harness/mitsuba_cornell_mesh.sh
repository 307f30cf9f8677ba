#!/usr/bin/env bash
# Regenerate tests/refs/cornell-mesh.exr (and its noise estimate, cornell-mesh.txt) with Mitsuba 3.
# The environment (Python >= 3.11, Mitsuba's venv: MITSUBA_VENV, default target/mitsuba-venv) is
# harness/mitsuba_env.sh's. Arguments go to the Python script:
#   harness/mitsuba_cornell_mesh.sh                      # the committed reference (~40 min, 2 cores)
#   harness/mitsuba_cornell_mesh.sh --two-sided --spp 256 --passes 8 --out /tmp/two-sided.exr
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
. "$root/harness/mitsuba_env.sh"
exec "$venv/bin/python" "$root/harness/mitsuba_cornell_mesh.py" "$@"
