#!/bin/bash
# Error rates of the evidence tests on the development split (docs/decision.md):
# each test weighed alone over seeds 0 and 1 of every scene family (60 frames),
# its firings counted against the truth by the rule tallies of `specular
# detect --rules`; then scripts/calibrate-evidence.py prints the rates.
#   scripts/calibrate-evidence.sh [OUT]   (default /tmp/calibrate-evidence)
#   TESTS="depth echo-order" scripts/calibrate-evidence.sh   (only those tests)
set -euo pipefail
OUT=${1:-/tmp/calibrate-evidence}
BIN=${BIN:-target/release/specular}
mkdir -p "$OUT"
for t in ${TESTS:-seen-space seen-surface image-support frame-free-space depth echo-strength echo-order level-surface seen-through}; do
  printf '[plane_map.weighing]\ntests = ["%s"]\n' "$t" > "$OUT/$t.toml"
  for f in $("$BIN" simulate --list-families); do
    for s in 0 1; do
      "$BIN" detect --family "$f" --seed "$s" --scene-frames 60 --rules --lean \
        --config "$OUT/$t.toml" --out "$OUT/o-$t-$f-$s" --force > /dev/null
    done
  done
done
python3 "$(dirname "$0")/calibrate-evidence.py" "$OUT"
