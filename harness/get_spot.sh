#!/usr/bin/env bash
# Put Keenan Crane's Spot (public domain) at scenes/models/spot.obj from a clone of
# alecjacobson/common-3d-test-models (its work tree or git directory), at the pinned commit,
# checking the SHA-256 recorded in scenes/models/README.md.
#   harness/get_spot.sh ~/src/common-3d-test-models
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
commit=8a4f8642acaf43f9cd7b67858a1502e1055ef202
sha=0738b5e8608fed74e5e8c7aa8dd0af97b4b74f9f6cbf7aac84cd7e40b2e44a75
if [ $# -ne 1 ]; then
    echo "usage: $0 CLONE-OF-common-3d-test-models" >&2
    exit 2
fi
out="$root/scenes/models/spot.obj"
tmp="$out.tmp"
if [ -d "$1/.git" ] || [ -d "$1/objects" ]; then
    git_dir="$1"
    [ -d "$1/.git" ] && git_dir="$1/.git"
    git --git-dir="$git_dir" show "$commit:data/spot.obj" > "$tmp"
else
    echo "$1: not a git clone" >&2
    exit 2
fi
if ! echo "$sha  $tmp" | sha256sum --check --status; then
    rm -f "$tmp"
    echo "spot.obj at $commit does not have the recorded SHA-256 $sha" >&2
    exit 1
fi
mv "$tmp" "$out"
echo "wrote $out"
