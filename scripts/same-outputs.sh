#!/usr/bin/env bash
# Same outputs before and after: builds BASE_REV and the work tree, runs both
# binaries on the same inputs and compares every result file byte for byte.
# A refactoring (moving code, new seams) must leave them identical.
#
#   scripts/same-outputs.sh BASE_REV [FRAMES_DIR]
#
# FRAMES_DIR: real 3DRef frames with their poses in hesai_pose.txt (default:
# the ten shared frames, ../shared/data/3dref-seq1-demo). The runs:
#
#   simulate  office, corridor and lobby, 6 frames each, by each
#             binary (the frames, poses.txt and planes.json are compared)
#   detect    FRAMES_DIR and each scene (as the base simulated it, so both
#             binaries read the same paths), plane-optimized and single-scan
#   slam      the same inputs, with classification
#
# Compared: every file of every run (predictions/*.label, planes.json,
# poses.txt, around_corner.ply, metrics.json, frames.csv, ...) except the
# ones that hold wall-clock times (report.md, run.mcap, timings.png and the
# plots); in metrics.json the timing fields ("timings", "wall_s",
# "frames_per_s", "frames_per_cpu_second", the back-end report's "seconds")
# and the provenance ("specular": version, commit) are removed first, and frames.csv loses its time_ms column. Exit status 0 when
# everything is identical, 1 with the differing files listed otherwise.
#
# Environment: CARGO_TARGET_DIR is the work tree's target directory (default
# ./target); BASE_TARGET_DIR the base's (default: CARGO_TARGET_DIR-base), so
# repeated runs rebuild only what changed. SAME_OUTPUTS_TMP: where the
# base's source and the outputs go (default: a fresh mktemp directory,
# removed at the end unless KEEP=1).
set -euo pipefail

usage() {
    sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
}
[ $# -ge 1 ] || usage
base_rev=$1
repo=$(cd "$(dirname "$0")/.." && pwd)
frames=${2:-$repo/../shared/data/3dref-seq1-demo}
[ -d "$frames" ] || { echo "error: no frame directory $frames" >&2; exit 2; }
frames=$(cd "$frames" && pwd)
[ -f "$frames/hesai_pose.txt" ] || { echo "error: no $frames/hesai_pose.txt" >&2; exit 2; }
base_sha=$(git -C "$repo" rev-parse --verify "$base_rev^{commit}")
work_target=${CARGO_TARGET_DIR:-$repo/target}
base_target=${BASE_TARGET_DIR:-$work_target-base}
tmp=${SAME_OUTPUTS_TMP:-$(mktemp -d /tmp/same-outputs.XXXXXX)}
mkdir -p "$tmp"
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$tmp"' EXIT

log() { echo "same-outputs: $*" >&2; }

# Base source: an export of the commit (no worktree left behind).
rm -rf "$tmp/base-src"
mkdir -p "$tmp/base-src"
git -C "$repo" archive "$base_sha" | tar -x -C "$tmp/base-src"
log "building base ${base_sha:0:7} into $base_target"
(cd "$tmp/base-src" && CARGO_TARGET_DIR=$base_target cargo build --release --quiet --bin specular)
log "building the work tree into $work_target"
(cd "$repo" && CARGO_TARGET_DIR=$work_target cargo build --release --quiet --bin specular)

scenes=(office corridor lobby)

# The simulated scenes, made by binary $1 into $2.
simulate_all() {
    local bin=$1 out=$2
    mkdir -p "$out"
    for scene in "${scenes[@]}"; do
        "$bin" --quiet simulate --scene "$scene" --frames 6 --out "$out/sim-$scene" >/dev/null
    done
}

# Every run of binary $1 into $2, on the real frames and on the scenes
# simulated by the base (the same input paths for both binaries: some
# outputs name their input).
run_all() {
    local bin=$1 out=$2
    mkdir -p "$out"
    local q=(--quiet)
    # name|frame directory|pose file
    local inputs=("real|$frames|$frames/hesai_pose.txt")
    for scene in "${scenes[@]}"; do
        inputs+=("$scene|$tmp/base/sim-$scene/frames|$tmp/base/sim-$scene/poses.txt")
    done
    for input in "${inputs[@]}"; do
        local name dir pose_file
        IFS='|' read -r name dir pose_file <<<"$input"
        local poses=(--poses "$pose_file") truth=(--gt-poses "$pose_file")
        "$bin" "${q[@]}" detect --frames "$dir" "${poses[@]}" --no-mcap \
            --out "$out/detect-po-$name" >/dev/null
        "$bin" "${q[@]}" detect --frames "$dir" --method single-scan --no-mcap \
            --out "$out/detect-ss-$name" >/dev/null
        "$bin" "${q[@]}" slam --frames "$dir" "${truth[@]}" \
            --out "$out/slam-$name" >/dev/null
    done
}

# Timing-free copies of the files that carry times; the rest as they are.
normalise() {
    local out=$1
    find "$out" -name metrics.json | while read -r f; do
        jq -S 'del(.specular) | walk(if type == "object" then
                 del(.timings, .wall_s, .frames_per_s, .seconds,
                     .frames_per_cpu_second) else . end)' "$f" >"$f.tmp"
        mv "$f.tmp" "$f"
    done
    find "$out" -name frames.csv | while read -r f; do
        python3 - "$f" <<'EOF'
import csv, sys
path = sys.argv[1]
rows = list(csv.reader(open(path)))
drop = [i for i, h in enumerate(rows[0]) if h == "time_ms"]
with open(path, "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    for r in rows:
        w.writerow([c for i, c in enumerate(r) if i not in drop])
EOF
    done
    find "$out" \( -name report.md -o -name run.mcap -o -name '*.png' \) -delete
}

log "running base"
simulate_all "$base_target/release/specular" "$tmp/base"
run_all "$base_target/release/specular" "$tmp/base"
log "running work tree"
simulate_all "$work_target/release/specular" "$tmp/work"
run_all "$work_target/release/specular" "$tmp/work"
normalise "$tmp/base"
normalise "$tmp/work"

files=$(cd "$tmp/base" && find . -type f | sort)
count=$(echo "$files" | wc -l)
if diff -r -q "$tmp/base" "$tmp/work"; then
    echo "same-outputs: identical: $count files (base ${base_sha:0:7} vs work tree $(git -C "$repo" rev-parse --short HEAD)$(git -C "$repo" diff --quiet HEAD || echo '+changes'))"
    (cd "$tmp/base" && find . -name '*.label' | wc -l | xargs echo "  prediction files:")
    (cd "$tmp/base" && find . \( -name planes.json -o -name poses.txt -o -name metrics.json \) | wc -l | xargs echo "  planes.json, poses.txt, metrics.json:")
else
    echo "same-outputs: DIFFERENT (outputs kept in $tmp)" >&2
    trap - EXIT
    exit 1
fi
