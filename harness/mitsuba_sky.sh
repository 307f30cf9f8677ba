#!/usr/bin/env bash
# Regenerate tests/refs/sky.exr (and its noise estimate, sky.txt) with Mitsuba 3
# (harness/mitsuba_sky.py), lit by ptui's own sky texels (`cargo xtask sky-map`).
#   harness/mitsuba_sky.sh                                          # the committed reference (~40 min, 2 cores)
#   harness/mitsuba_sky.sh --spp 256 --passes 8 --out /tmp/sky.exr  # a quick one
# The environment (Python >= 3.11, Mitsuba's venv, the xtask built): harness/mitsuba_env.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
. "$root/harness/mitsuba_env.sh"
exec "$venv/bin/python" "$root/harness/mitsuba_sky.py" "$@"
