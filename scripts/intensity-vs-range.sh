#!/usr/bin/env bash
# Echo intensity against range on ascii 3DRef frames: per range bin, the
# median intensity of labelled-Normal returns met within 37 degrees of
# normal incidence (|cos| > 0.8, from the files' own nx ny nz), and the
# share of them at the sensor's ceiling of 255. A sensor that reports the
# raw return power loses a factor of 4 per doubling of the range; one that
# reports a range-compensated reflectivity keeps its median where nothing
# saturates. The numbers of datasets/README.md ("Physics, in short").
#
#   scripts/intensity-vs-range.sh [FRAMES_DIR]
#
# FRAMES_DIR: ascii PLY frames with x y z nx ny nz intensity ring return
# label, in that order (default: the ten shared frames,
# ../shared/data/3dref-seq1-demo). Needs awk and sort.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-../shared/data/3dref-seq1-demo}
# Bins of a quarter octave of range: bin k holds ranges in [2^(k/4), 2^((k+1)/4)) m.
for f in "$dir"/*.ply; do
  awk 'BEGIN { body = 0 }
       body == 0 { if ($1 == "end_header") body = 1; next }
       $10 == 1 {
         r = sqrt($1 * $1 + $2 * $2 + $3 * $3)
         n = sqrt($4 * $4 + $5 * $5 + $6 * $6)
         if (r <= 0.5 || n <= 0) next
         c = ($1 * $4 + $2 * $5 + $3 * $6) / (r * n)
         if (c < 0) c = -c
         if (c > 0.8) printf "%d %s\n", int(4 * log(r) / log(2) + 100) - 100, $7
       }' "$f"
done | sort -k1,1n -k2,2g | awk '
  function flush() {
    if (n >= 200) {
      m = (n % 2) ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
      printf "| %5.1f-%5.1f | %6d | %6.1f | %5.1f |\n", 2 ^ (bin / 4), 2 ^ ((bin + 1) / 4), n, m, 100 * sat / n
    }
    n = 0; sat = 0
  }
  BEGIN { print "| range, m | returns | median intensity | at 255, % |"; print "|---|---:|---:|---:|"; bin = "" }
  { if ($1 != bin) { if (bin != "") flush(); bin = $1 } v[++n] = $2; if ($2 >= 255) sat++ }
  END { flush() }'
