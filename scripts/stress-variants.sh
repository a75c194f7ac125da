#!/usr/bin/env bash
# Stress variants of the built-in scenes: each is a scene file of
# datasets/scenes/ with one line changed (a faster walk, twice the range
# noise, coated partitions), run through `specular detect` with the true
# poses. Prints the Markdown table of datasets/README.md ("Stress
# variants"). The benchmark scenes are what the method was tuned on; these
# are what it was not, so a change that helps the benchmark and breaks a
# variant is tuned to the scenes, not to the physics.
#
#   scripts/stress-variants.sh [CONFIG]
#
# CONFIG: a built-in configuration name or a TOML file (default: default).
# Environment: BIN, the specular binary (default: target/release/specular,
# built first with `cargo build --release`). Needs jq. About two minutes
# on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
config=${1:-default}
bin=${BIN:-target/release/specular}
if [ -z "${BIN:-}" ]; then
    cargo build --release --quiet
fi
command -v jq >/dev/null || { echo "error: jq is needed to read metrics.json" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "| variant (change to the scene file) | mIoU | refl. precision | normal recall | obstacle IoU | glass IoU |"
echo "|---|---:|---:|---:|---:|---:|"

# variant SCENE SED-EXPRESSION DESCRIPTION: the scene file with the
# expression applied (an error when it changes nothing: the scene file moved
# on), through detect, as one row of the table.
variant() {
    local scene=$1 expr=$2 description=$3
    local file="$tmp/variant.toml" out="$tmp/out"
    sed "$expr" "datasets/scenes/$scene.toml" >"$file"
    if cmp -s "datasets/scenes/$scene.toml" "$file"; then
        echo "error: '$expr' changes nothing in datasets/scenes/$scene.toml" >&2
        exit 1
    fi
    "$bin" detect --scene "$file" --out "$out" --lean --quiet --force --config "$config" >/dev/null
    jq -r --arg name "$description" '
        def f2: (. * 100 | round) as $n
            | ($n / 100 | floor | tostring) + "."
              + ($n % 100 | tostring | if length < 2 then "0" + . else . end);
        def class($c; $k): (.classes[] | select(.class == $c) | .[$k]) // null
            | if . == null then "–" else f2 end;
        "| \($name) | \(.miou | f2) | \(class("reflection"; "precision")) | \(class("normal"; "recall")) | \(class("obstacle"; "iou")) | \(class("glass"; "iou")) |"
    ' "$out/metrics.json"
}

variant corridor 's/^speed = 1.0$/speed = 1.5/; s/^frames = 720$/frames = 480/' \
    'corridor, `speed = 1.5`, `frames = 480`'
variant office 's/^speed = 0.35$/speed = 0.6/' 'office, `speed = 0.6`'
variant lobby 's/^range_noise = 0.01$/range_noise = 0.02/' 'lobby, `range_noise = 0.02`'
variant glass-loop 's/^range_noise = 0.01$/range_noise = 0.02/' 'glass-loop, `range_noise = 0.02`'
variant corridor \
    's/^partition = { type = "glass", reflectance = 0.12, transmittance = 0.8,/partition = { type = "glass", reflectance = 0.25, transmittance = 0.6,/' \
    'corridor, partitions coated (`reflectance = 0.25, transmittance = 0.6`)'
