#!/usr/bin/env bash
# Load time and memory of a large textured model (issue 47): the easy-gltf head
# (harness/get_easy_gltf.sh) subdivided five times and its texture enlarged by
# `cargo xtask large-model` (2,551,808 triangles; an 8192 x 8192 and a 4096 x 4096 PNG, 240 MiB
# of texels), opened as a bare model by `ptui render` at 1 spp, RUNS times: the scene build the
# summary reports, the wall time and the peak resident memory (GNU time). Numbers go to
# benches/HISTORY.md.
#   harness/large_model_bench.sh [RUNS]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
runs="${1:-5}"
model="$root/target/large/head-large.glb"
"$root/harness/get_easy_gltf.sh" >/dev/null
(cd "$root" && cargo build --release -q -p ptui -p xtask)
if [ ! -f "$model" ]; then
    "$root/target/release/xtask" large-model "$root/scenes/models/easy-gltf/head.glb" "$model"
fi
command -v /usr/bin/time >/dev/null || { echo "needs GNU time (apt-get install time)" >&2; exit 1; }
echo "run  scene_build_s  wall_s  peak_rss_MiB"
for i in $(seq 1 "$runs"); do
    out="$(/usr/bin/time -f 'TIME %e %M' "$root/target/release/ptui" render "$model" --spp 1 \
        --size 320x240 --threads 2 -o /tmp/ptui-large-model.png --quiet 2>&1)"
    build="$(echo "$out" | sed -n 's/.*scene build \([0-9.]*\) ms.*/\1/p')"
    read -r _ wall rss <<<"$(echo "$out" | grep '^TIME')"
    awk -v i="$i" -v b="$build" -v w="$wall" -v r="$rss" \
        'BEGIN { printf "%3d  %13.2f  %6.2f  %12.0f\n", i, b / 1000, w, r / 1024 }'
done
