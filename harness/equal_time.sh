#!/usr/bin/env bash
# Equal-time RMSE, ptui against Mitsuba 3 on one scene (harness/equal_time.py):
#   harness/equal_time.sh scenes/torus-knot.toml tests/refs/torus-knot.exr [--pairs 3] [--seconds 10]
#   harness/equal_time.sh scenes/spot.toml tests/refs/spot.exr
# Sets up Mitsuba and builds ptui (harness/mitsuba_env.sh), then alternates ptui and Mitsuba runs
# on 2 threads.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
. "$root/harness/mitsuba_env.sh"
exec "$venv/bin/python" "$root/harness/equal_time.py" "$@"
