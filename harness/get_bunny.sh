#!/usr/bin/env bash
# Put the Stanford bunny at scenes/models/bunny.obj: the npm registry's `bunny` package (pinned
# version, its registry integrity checked), whose index.js holds positions and cells, written out
# as an OBJ by node and checked against the SHA-256 in scenes/models/README.md. Needs npm, node
# and python3; does nothing when the file is already there with that checksum.
#   harness/get_bunny.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
version=1.0.1
integrity="sha512-KsMt755E0AVYjeUnQeOPtVNGuDLiWjJ6VIoyywLmVx5R6QliuL5AS0X/gi+ORDDlBZfOaDBAqdqCv5XAlF9tCQ=="
sha=86942669645225f4fa0fa0a9152e37a613a9f7125686b8aa3b91cfc068288b27
out="$root/scenes/models/bunny.obj"
if [ -f "$out" ] && echo "$sha  $out" | sha256sum --check --status; then
    echo "$out is in place"
    exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# Bounded waits, so a registry that cannot be reached fails in a minute or two, not five.
(cd "$tmp" && npm pack --silent --fetch-retries=1 --fetch-timeout=60000 "bunny@$version" >/dev/null)
tarball="$tmp/bunny-$version.tgz"
got="sha512-$(python3 -c 'import base64, hashlib, sys; print(base64.b64encode(hashlib.sha512(open(sys.argv[1], "rb").read()).digest()).decode())' "$tarball")"
if [ "$got" != "$integrity" ]; then
    echo "bunny@$version from the npm registry: integrity $got, expected $integrity" >&2
    exit 1
fi
tar -xzf "$tarball" -C "$tmp"
# OBJ: one `v` per position as index.js writes it, one `f` per cell (1-based), in file order.
node -e '
const b = require(process.argv[1]);
const lines = ["# Stanford bunny from the npm package bunny@" + process.argv[2] + " (harness/get_bunny.sh)"];
for (const p of b.positions) lines.push("v " + p.join(" "));
for (const c of b.cells) lines.push("f " + c.map((i) => i + 1).join(" "));
process.stdout.write(lines.join("\n") + "\n");
' "$tmp/package" "$version" > "$tmp/bunny.obj"
if ! echo "$sha  $tmp/bunny.obj" | sha256sum --check --status; then
    echo "the converted bunny.obj has SHA-256 $(sha256sum < "$tmp/bunny.obj" | cut -d' ' -f1), not the recorded $sha" >&2
    exit 1
fi
mkdir -p "$(dirname "$out")"
mv "$tmp/bunny.obj" "$out"
echo "wrote $out"
