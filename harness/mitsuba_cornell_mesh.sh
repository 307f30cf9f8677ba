#!/usr/bin/env bash
# Regenerate tests/refs/cornell-mesh.exr (and its noise estimate, cornell-mesh.txt) with Mitsuba 3.
# Makes its own virtual environment (Python >= 3.11, for tomllib) with harness/requirements.txt;
# MITSUBA_VENV picks where (default target/mitsuba-venv). Arguments go to the Python script:
#   harness/mitsuba_cornell_mesh.sh                      # the committed reference (~40 min, 2 cores)
#   harness/mitsuba_cornell_mesh.sh --two-sided --spp 256 --passes 8 --out /tmp/two-sided.exr
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="${MITSUBA_VENV:-$root/target/mitsuba-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q -r "$root/harness/requirements.txt"
exec "$venv/bin/python" "$root/harness/mitsuba_cornell_mesh.py" "$@"
