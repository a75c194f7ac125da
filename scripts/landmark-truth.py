"""The plane map against the simulator's reflective surfaces: landmarks
that match no true surface (ghosts), true surfaces seen in at least
MIN_VIEWS frames that no landmark matches (missed), per run.
A landmark matches a surface when their normals are within 8 deg, the
landmark's hull centroid lies within 0.3 m of the surface's plane and
their bounding boxes overlap (0.3 m slack).
    for f in $(specular simulate --list-families); do for s in 0 1 2; do
      specular detect --family $f --seed $s --scene-frames 100 --lean --out runs/$f-$s
      specular simulate --family $f --seed $s --frames 100 --out truth/$f-$s
    done; done
    python3 scripts/landmark-truth.py runs truth
Needs numpy."""
import glob
import json
import os
import sys

import numpy as np

MIN_VIEWS = 10
COS = np.cos(np.radians(8.0))


def matches(landmark, surface):
    n, h = np.array(landmark["normal"]), np.array(landmark["hull"])
    tn, th = np.array(surface["normal"]), np.array(surface["hull"])
    if abs(n @ tn) < COS or abs(tn @ h.mean(0) + surface["d"]) > 0.3:
        return False
    return bool(np.all(h.max(0) >= th.min(0) - 0.3) and np.all(h.min(0) <= th.max(0) + 0.3))


def main(runs, truth):
    landmarks = ghosts = seen = missed = 0
    for planes in sorted(glob.glob(os.path.join(runs, "*", "planes.json"))):
        run = os.path.basename(os.path.dirname(planes))
        truth_file = os.path.join(truth, run, "planes.json")
        if not os.path.exists(truth_file):
            print(f"{run}: no {truth_file}, skipped", file=sys.stderr)
            continue
        surfaces = [t for t in json.load(open(truth_file)) if t.get("observations", 0) > 0]
        found = json.load(open(planes))
        lost = [l for l in found if not any(matches(l, t) for t in surfaces)]
        wanted = [t for t in surfaces if t["observations"] >= MIN_VIEWS]
        unmatched = [t for t in wanted if not any(matches(l, t) for l in found)]
        landmarks += len(found)
        ghosts += len(lost)
        seen += len(wanted)
        missed += len(unmatched)
        for l in lost:
            n = ", ".join(f"{x:.2f}" for x in l["normal"])
            print(f"{run}: ghost landmark {l['id']} normal ({n}) d {l['d']:.2f} "
                  f"observations {l['observations']} P(mirror) {l.get('mirror_probability')}")
        for t in unmatched:
            size = np.ptp(np.array(t["hull"]), axis=0)
            print(f"{run}: missed {t['material']} {t['id']} ({size[0]:.1f} x {size[1]:.1f} x "
                  f"{size[2]:.1f} m, in {t['observations']} frames)")
    print(f"{ghosts} of {landmarks} landmarks match no true surface; "
          f"{missed} of {seen} surfaces seen in >= {MIN_VIEWS} frames have no landmark")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
