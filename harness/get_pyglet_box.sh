#!/usr/bin/env bash
# Put pyglet's example model at scenes/models/pyglet-box/: box.obj (a cube exported by Blender
# 2.78, with texture coordinates and normals), its box.mtl (a `map_Kd` texture, `Ks` and `Ns`)
# and pyglet.png. From PyPI: the source distribution of `pyglet` (pinned version) fetched by pip,
# its SHA-256 and each file's checked against those recorded in scenes/models/README.md. Needs
# python3 with pip; does nothing when the files are already there.
#   harness/get_pyglet_box.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
version=2.1.19
sdist_sha=77fae024df940c60917ba604bab9b7e26306d66734186634b698c708cdd9f4be
out="$root/scenes/models/pyglet-box"
sums="74b8641c4e58f62a746d138663e4379f84d10f307fdf611db39cf0e113be94d1  box.obj
b126063aa55471e33eb37b1400bce2d6ec660f9ccc9a6d0fcd9f5ca54d60cfad  box.mtl
593b1fe03b22cd8205f4c4bc0a8fff1e2c8836e5cc44d5ff7e4d509afa790406  pyglet.png"
if [ -d "$out" ] && (cd "$out" && echo "$sums" | sha256sum --check --status); then
    echo "$out is in place"
    exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# The source distribution (the wheel has no examples); bounded waits, so a registry that cannot
# be reached fails in a minute or two.
python3 -m pip download --quiet --no-deps --no-binary pyglet --timeout 60 --retries 1 \
    --dest "$tmp" "pyglet==$version" >&2
sdist="$tmp/pyglet-$version.tar.gz"
if ! echo "$sdist_sha  $sdist" | sha256sum --check --status; then
    echo "pyglet-$version.tar.gz from PyPI: SHA-256 $(sha256sum < "$sdist" | cut -d' ' -f1), expected $sdist_sha" >&2
    exit 1
fi
tar -xzf "$sdist" -C "$tmp" "pyglet-$version/examples/model"
if ! (cd "$tmp/pyglet-$version/examples/model" && echo "$sums" | sha256sum --check --status); then
    echo "pyglet-$version: examples/model does not have the recorded SHA-256 sums" >&2
    exit 1
fi
mkdir -p "$out"
for f in box.obj box.mtl pyglet.png; do
    mv "$tmp/pyglet-$version/examples/model/$f" "$out/$f"
done
echo "wrote $out"
