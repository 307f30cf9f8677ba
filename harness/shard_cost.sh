#!/usr/bin/env bash
# The cost of sharding (issue 36): CPU time (user + sys) of N shards against the single render
# of the same image, one thread per process (so no thread waits for another and the sum of the
# processes' CPU time is their work); with the adaptive pilot rendered by every shard past pass
# 0, and with it rendered once (--pilot); then the merge's time and throughput.
#
# usage: harness/shard_cost.sh [SCENE] [SIZE] [SPP] [N] [ROUNDS]   (PTUI=binary to use)
set -euo pipefail
cd "$(dirname "$0")/.."
PTUI=${PTUI:-target/release/ptui}
SCENE=${1:-cornell} SIZE=${2:-640x480} SPP=${3:-1024} N=${4:-8} ROUNDS=${5:-1}
dir=$(mktemp -d)
# On a stop, let a running render write its last checkpoint before its folder goes.
trap 'wait; rm -rf "$dir"' EXIT
# CPU seconds of one command (GNU time).
cpu() { /usr/bin/time -f "%U %S %e" -o "$dir/t" "$@" >/dev/null; awk '{print $1 + $2}' "$dir/t"; }
wall() { awk '{print $3}' "$dir/t"; }
common=(--size "$SIZE" --spp "$SPP" --threads 1 -q)
echo "scene $SCENE $SIZE, $SPP spp, $N shards, 1 thread per process"
for round in $(seq 1 "$ROUNDS"); do
    single=$(cpu "$PTUI" render "$SCENE" "${common[@]}" -o "$dir/single.film")
    echo "round $round: single $single s CPU"
    shards=0
    for i in $(seq 0 $((N - 1))); do
        t=$(cpu "$PTUI" render "$SCENE" "${common[@]}" --shard "$i/$N" -o "$dir/p$i.film")
        shards=$(awk -v a="$shards" -v b="$t" 'BEGIN {print a + b}')
        echo "round $round: shard $i/$N $t s CPU"
    done
    pilot=$(cpu "$PTUI" render "$SCENE" --size "$SIZE" --spp 16 --threads 1 -q -o "$dir/pilot.film")
    piloted=$pilot
    for i in $(seq 0 $((N - 1))); do
        t=$(cpu "$PTUI" render "$SCENE" "${common[@]}" --shard "$i/$N" --pilot "$dir/pilot.film" -o "$dir/q$i.film")
        piloted=$(awk -v a="$piloted" -v b="$t" 'BEGIN {print a + b}')
        echo "round $round: piloted shard $i/$N $t s CPU"
    done
    m=$(cpu "$PTUI" merge "$dir"/p[0-9]*.film -o "$dir/merged.film" --require-complete)
    mwall=$(wall)
    bytes=$(cat "$dir"/p[0-9]*.film "$dir/merged.film" | wc -c)
    awk -v r="$round" -v s="$single" -v a="$shards" -v p="$piloted" -v pl="$pilot" -v m="$m" -v w="$mwall" -v b="$bytes" 'BEGIN {
        printf "round %d: single %.1f s CPU; %s shards %.1f s (%.3fx); with --pilot %.1f s incl. the pilot film %.1f s (%.3fx)\n",
            r, s, "'"$N"'", a, a / s, p, pl, p / s
        printf "round %d: merge %.2f s CPU, %.2f s wall, %.0f MB read+written (%.0f MB/s)\n", r, m, w, b / 1e6, b / 1e6 / (w > 0 ? w : 0.01)
    }'
done
