#!/usr/bin/env bash
# Put the glTF test models of the crates.io package `easy-gltf` (pinned version) at
# scenes/models/easy-gltf/: head.glb (a textured head exported by Blender, with its camera and
# three point lights) and cube_classic.gltf with its .bin and cube.png beside it. cargo fetches
# the crate through a throwaway manifest (checking it against the registry index's checksum);
# the crate's SHA-256 and each file's are then checked against those recorded in
# scenes/models/README.md. Needs cargo; does nothing when the files are already there.
#   harness/get_easy_gltf.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
version=1.1.5
crate_sha=1203d5e3b06d11431cd680b7d89fe3565ea797e948a3869aa791f10855b02175
out="$root/scenes/models/easy-gltf"
sums="ae9d98561b717c926bb0af954e35ec8daa0bbc9e83a2027b3f17a771d94d69cc  head.glb
113a6abdf7a1298d4bfa42800655d716581fdf9df6af5141f8fc0f1b8fef7d3e  cube_classic.gltf
60f0cc476d265c1fff27ac1e8bbcd6faa1f0fc05b55506503ed2277be9a14952  cube_classic.bin
80b2f2e8708b8526e785cfd6211a739bf985e59e78d560363c1b2305191d2b1f  cube.png"
if [ -d "$out" ] && (cd "$out" && echo "$sums" | sha256sum --check --status); then
    echo "$out is in place"
    exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/fetch/src"
: > "$tmp/fetch/src/lib.rs"
cat > "$tmp/fetch/Cargo.toml" <<TOML
[package]
name = "fetch-easy-gltf"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
easy-gltf = "=$version"

[workspace]
TOML
# Bounded waits, so a registry that cannot be reached fails in a minute or two.
CARGO_NET_RETRY=1 CARGO_HTTP_TIMEOUT=60 cargo fetch --quiet --manifest-path "$tmp/fetch/Cargo.toml"
crate=""
for c in "${CARGO_HOME:-$HOME/.cargo}"/registry/cache/*/"easy-gltf-$version.crate"; do
    [ -f "$c" ] && echo "$crate_sha  $c" | sha256sum --check --status && crate="$c" && break
done
if [ -z "$crate" ]; then
    echo "easy-gltf@$version: no crate with SHA-256 $crate_sha in cargo's cache after cargo fetch" >&2
    exit 1
fi
tar -xzf "$crate" -C "$tmp" "easy-gltf-$version/tests"
if ! (cd "$tmp/easy-gltf-$version/tests" && echo "$sums" | sha256sum --check --status); then
    echo "easy-gltf@$version: its test models do not have the recorded SHA-256 sums" >&2
    exit 1
fi
mkdir -p "$out"
for f in head.glb cube_classic.gltf cube_classic.bin cube.png; do
    mv "$tmp/easy-gltf-$version/tests/$f" "$out/$f"
done
echo "wrote $out"
