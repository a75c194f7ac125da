"""Where the weighed decision errs behind reflective planes: the rule
tallies of `specular detect --rules` runs (metrics.json) summed, per rule
that decided, the reflections called real and the obstacles called
reflections (3DRef label ids: 1 normal, 5 reflection, 6 obstacle).
A point that no test weighed is decided by its landmark's prior (`prior/`);
a point whose beam crossed no reflective landmark is `no-pane/`.
    python3 scripts/decision-errors.py OUT/o-*/metrics.json
    python3 scripts/decision-errors.py --by-family runs/F-S/metrics.json ...
With --by-family, a table per family as well: the family is the name of
the run's directory up to its last '-' (runs/atrium-4 is atrium)."""
import collections
import json
import os
import sys

REFLECTION, OBSTACLE = 5, 6


def tally(paths):
    """Per rule: [R right, R wrong, O right, O wrong]."""
    rows = collections.defaultdict(lambda: [0, 0, 0, 0])
    for path in paths:
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
    return rows


def show(rows):
    total = [sum(r[i] for r in rows.values()) for i in range(4)]
    print(f"{'rule':22s} {'R right':>10s} {'R wrong':>10s} {'O right':>10s} {'O wrong':>10s}")
    for rule, r in sorted(rows.items(), key=lambda kv: -(kv[1][1] + kv[1][3])):
        if sum(r):
            print(f"{rule:22s} {r[0]:10d} {r[1]:10d} {r[2]:10d} {r[3]:10d}")
    print(f"{'all':22s} {total[0]:10d} {total[1]:10d} {total[2]:10d} {total[3]:10d}")


args = sys.argv[1:]
by_family = "--by-family" in args
paths = [a for a in args if a != "--by-family"]
if by_family:
    families = collections.defaultdict(list)
    for path in paths:
        run = os.path.basename(os.path.dirname(os.path.abspath(path)))
        families[run.rsplit("-", 1)[0]].append(path)
    for family, group in sorted(families.items()):
        print(f"== {family} ({len(group)} runs)")
        show(tally(group))
    print("== all")
show(tally(paths))
