#!/bin/sh
# Renders the painterly pictures of docs/SCENES.md into docs/painterly/ (from the repository root):
#   sh docs/painterly/render.sh
# Every picture is one `ptui render` command; seeds are the default (0), so reruns are identical.
set -e
cargo build --release
ptui=target/release/ptui
out=docs/painterly
r() { "$ptui" render -q "$@"; }

# path vs painterly (defaults: world-z hemisphere, correlation 1, stroke 16, strength 1)
r smallpaint --spp 16 --integrator path      -o $out/smallpaint-path.png
r smallpaint --spp 16 --integrator painterly -o $out/smallpaint-painterly.png
r cornell --size 256x192 --spp 64 --integrator path      -o $out/cornell-path.png
r cornell --size 256x192 --spp 64 --integrator painterly -o $out/cornell-painterly.png

# one parameter at a time, the others at their defaults (smallpaint, 192x192, 16 spp);
# defaults.png is the column every row shares (world-z, correlation 1, stroke 16, strength 1)
p() { name=$1; shift; r smallpaint --size 192x192 --spp 16 --integrator painterly "$@" -o $out/$name.png; }
p defaults
p hemisphere-normal --hemisphere normal
p correlation-0     --correlation 0
p correlation-0.5   --correlation 0.5
p stroke-1  --stroke 1
p stroke-4  --stroke 4
p stroke-64 --stroke 64
p strength-0    --strength 0
p strength-0.25 --strength 0.25
p strength-0.5  --strength 0.5
