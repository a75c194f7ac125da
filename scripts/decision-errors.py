"""Where the weighed decision errs behind reflective planes: the rule
tallies of `specular detect --rules` runs (metrics.json) summed, per rule
that decided, the reflections called real and the obstacles called
reflections (3DRef label ids: 1 normal, 5 reflection, 6 obstacle).
A point that no test weighed is decided by its landmark's prior (`prior/`).
    python3 scripts/decision-errors.py OUT/o-*/metrics.json"""
import collections
import json
import sys

REFLECTION, OBSTACLE = 5, 6
rows = collections.defaultdict(lambda: [0, 0, 0, 0])  # R right, R wrong, O right, O wrong
for path in sys.argv[1:]:
    for key, counts in json.load(open(path))["rules"].items():
        rule, predicted = key.split("/")
        row = rows[rule]
        if predicted == "reflection":
            row[0] += counts[REFLECTION]
            row[3] += counts[OBSTACLE]
        elif predicted in ("obstacle", "normal"):
            row[1] += counts[REFLECTION]
            row[2] += counts[OBSTACLE]
        else:  # unclassified: neither right
            row[1] += counts[REFLECTION]
            row[3] += counts[OBSTACLE]
total = [sum(r[i] for r in rows.values()) for i in range(4)]
print(f"{'rule':22s} {'R right':>10s} {'R wrong':>10s} {'O right':>10s} {'O wrong':>10s}")
for rule, r in sorted(rows.items(), key=lambda kv: -(kv[1][1] + kv[1][3])):
    if sum(r):
        print(f"{rule:22s} {r[0]:10d} {r[1]:10d} {r[2]:10d} {r[3]:10d}")
print(f"{'all':22s} {total[0]:10d} {total[1]:10d} {total[2]:10d} {total[3]:10d}")
