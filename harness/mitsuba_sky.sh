#!/usr/bin/env bash
# Regenerate tests/refs/sky.exr (and its noise estimate, sky.txt) with Mitsuba 3.
# Makes its own virtual environment (Python >= 3.11, for tomllib) with harness/requirements.txt;
# MITSUBA_VENV picks where (default target/mitsuba-venv). Arguments go to the Python script:
#   harness/mitsuba_sky.sh                      # the committed reference (~20 min, 2 cores)
#   harness/mitsuba_sky.sh --spp 256 --passes 8 --out /tmp/sky.exr   # a quick one
# The script runs `cargo xtask sky-map` to get ptui's sky texels.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="${MITSUBA_VENV:-$root/target/mitsuba-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q -r "$root/harness/requirements.txt"
exec "$venv/bin/python" "$root/harness/mitsuba_sky.py" "$@"
