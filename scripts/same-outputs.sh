#!/usr/bin/env bash
# Same outputs before and after: builds BASE_REV and the work tree, runs both
# binaries on the same inputs and compares every result file byte for byte.
# A refactoring (moving code, new seams) must leave them identical.
#
#   scripts/same-outputs.sh BASE_REV [FRAMES_DIR]
#
# FRAMES_DIR: real 3DRef frames with their poses (default: the ten shared
# frames, ../shared/data/3dref-seq1-demo). The runs:
#
#   simulate  office, corridor and mirror-room, 6 frames each (the frames,
#             poses.txt and planes.json the simulator writes are compared too)
#   detect    FRAMES_DIR and each scene, plane-optimized (default method)
#             and single-scan
#   slam      FRAMES_DIR and each scene, with classification
#
# Compared: every file of every run (predictions/*.label, planes.json,
# poses.txt, around_corner.ply, metrics.json, frames.csv, ...) except the
# ones that hold wall-clock times (report.md, run.mcap, timings.png and the
# plots); in metrics.json the timing fields ("timings", "wall_s",
# "frames_per_s") and the provenance ("specular": version, commit) are
# removed first, and frames.csv loses its time_ms column. Exit status 0 when
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

scenes=(office corridor mirror-room)

# Every run of one binary into $2.
run_all() {
    local bin=$1 out=$2
    mkdir -p "$out"
    local q=(--quiet)
    for scene in "${scenes[@]}"; do
        "$bin" "${q[@]}" simulate --scene "$scene" --frames 6 --out "$out/sim-$scene" >/dev/null
    done
    local inputs=("real:$frames")
    for scene in "${scenes[@]}"; do inputs+=("$scene:$out/sim-$scene"); done
    for input in "${inputs[@]}"; do
        local name=${input%%:*} dir=${input#*:}
        local pose_file=$dir/poses.txt
        [ -f "$pose_file" ] || pose_file=$dir/hesai_pose.txt
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
                 del(.timings, .wall_s, .frames_per_s) else . end)' "$f" >"$f.tmp"
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
run_all "$base_target/release/specular" "$tmp/base"
log "running work tree"
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
