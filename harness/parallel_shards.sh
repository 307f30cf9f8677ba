#!/usr/bin/env bash
# CI (issue 36): render a scene's shards locally with GNU parallel (-j2), merge them, and check
# the merged image is the single render's. The check compares the linear EXRs byte for byte:
# the merged film's mean is the single render's to within 1e-15 relative (docs/FILM.md), so
# its f32 rounding is the same unless a mean lies within that of an f32 rounding boundary;
# scene, settings and seed are fixed, so the outcome is too. It also compares the tonemapped
# PNGs, and checks that argument order does not change the merged film's bytes.
#
# usage: harness/parallel_shards.sh   (PTUI=binary to use; default target/release/ptui)
set -euo pipefail
cd "$(dirname "$0")/.."
PTUI=${PTUI:-target/release/ptui}
command -v parallel >/dev/null || { echo "GNU parallel is required (apt-get install parallel)"; exit 1; }
[ -x "$PTUI" ] || { echo "$PTUI: build it first (cargo build --release)"; exit 1; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
N=4
args=(cornell --size 64x48 --spp 40 --threads 1 -q)
"$PTUI" render "${args[@]}" -o "$dir/single.exr" --checkpoint "$dir/single.film" >/dev/null
"$PTUI" render "${args[@]}" -o "$dir/single.png" >/dev/null
parallel --will-cite -j2 --halt now,fail=1 \
    "$PTUI" render "${args[@]}" --shard {}/$N -o "$dir/part-{}.film" ::: $(seq 0 $((N - 1))) >/dev/null
"$PTUI" merge "$dir"/part-*.film -o "$dir/merged.exr" --require-complete
"$PTUI" merge "$dir"/part-*.film -o "$dir/merged.png" --require-complete >/dev/null
"$PTUI" merge "$dir"/part-*.film -o "$dir/merged.film" --require-complete >/dev/null
"$PTUI" merge $(ls "$dir"/part-*.film | sort -r) -o "$dir/reversed.film" --require-complete >/dev/null
cmp "$dir/single.exr" "$dir/merged.exr"
cmp "$dir/single.png" "$dir/merged.png"
cmp "$dir/merged.film" "$dir/reversed.film"
# A missing shard is reported, and refused with --require-complete.
if "$PTUI" merge "$dir"/part-[012].film -o "$dir/partial.exr" --require-complete 2>"$dir/err"; then
    echo "merge accepted a missing shard with --require-complete"; exit 1
fi
grep -q "missing" "$dir/err"
echo "parallel shards: $N shards merged equal the single render (EXR and PNG byte for byte)"
