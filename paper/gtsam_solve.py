#!/usr/bin/env python3
"""Solve a specular graph file (docs/graph-format.md) with GTSAM, for the
side-by-side with `specular graph solve`.

    python3 paper/gtsam_solve.py GRAPH.json [--optimizer gn|lm] [--max-iterations 100]
        [--tolerance 1e-5]

Prints one JSON line: {"optimizer", "initial_error", "final_error",
"iterations", "seconds"}; `seconds` times `optimizer.optimize()` only
(graph construction excluded, as `specular graph solve` excludes reading).

Mapping (costs are 0.5 * sum of squared whitened residuals in both):
* pose_prior -> PriorFactorPose3, between -> BetweenFactorPose3. specular's
  tangent is (rho, phi), GTSAM's Pose3 tangent is (omega, v): the 6x6
  sqrt-information S is used with its column blocks swapped, S_g = S P^T.
  Both use the exponential map (X * Exp(d), Logmap(Z^-1 X_i^-1 X_j)).
* plane_observation -> OrientedPlane3Factor (same residual definition,
  3x3 sqrt-information as is).
* point_to_plane -> gtsam.CustomFactor in Python with the same residual and
  analytic Jacobians (slow: Python callbacks; use plane-to-plane graphs for
  timing).
* robust kernels -> noiseModel.Robust with mEstimator.Huber / Cauchy
  (GTSAM's loss equals specular's 0.5 * rho(s)).
* gauge: specular leaves fixed variables out of the system; here each fixed
  pose gets a PriorFactorPose3 at its initial value with sigma 1e-9 (its
  cost stays ~0). Fixed planes are not supported (error).
"""
import argparse
import json
import sys
import time

import numpy as np

import gtsam


def pose_of(t, q):
    x, y, z, w = q
    return gtsam.Pose3(gtsam.Rot3.Quaternion(w, x, y, z), gtsam.Point3(*t))


def key_of(k):
    kind, idx = k[0], int(k[1:])
    if kind == "x":
        return gtsam.symbol("x", idx)
    if kind == "p":
        return gtsam.symbol("p", idx)
    raise ValueError(f"bad key {k}")


def pose_sqrt_info(s):
    """(rho, phi)-ordered S -> (omega, v)-ordered S_g = S P^T."""
    s = np.asarray(s, dtype=float).reshape(6, 6)
    return np.hstack([s[:, 3:6], s[:, 0:3]])


def robust(noise, spec):
    if not spec or spec.get("kind", "none") == "none":
        return noise
    k = spec["k"]
    if spec["kind"] == "huber":
        m = gtsam.noiseModel.mEstimator.Huber.Create(k)
    elif spec["kind"] == "cauchy":
        m = gtsam.noiseModel.mEstimator.Cauchy.Create(k)
    else:
        raise ValueError(f"unknown robust kernel {spec}")
    return gtsam.noiseModel.Robust.Create(m, noise)


def hat(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def point_to_plane_factor(rec):
    """r = [sqrt(N)(n_s.c + d_s); L^T n_s] / sigma with C = L L^T."""
    m = rec["measurement"]
    count = m["count"]
    c = np.asarray(m["centroid"], dtype=float)
    scatter = np.asarray(m["scatter"], dtype=float).reshape(3, 3)
    inv_sigma = rec["sqrt_info"][0]
    w, v = np.linalg.eigh(0.5 * (scatter + scatter.T))
    lt = np.diag(np.sqrt(np.maximum(w, 0.0))) @ v.T
    sn = np.sqrt(count)
    kx, kp = key_of(rec["keys"][0]), key_of(rec["keys"][1])

    def error(this, values, jac):
        x = values.atPose3(kx)
        pl = values.atOrientedPlane3(kp)
        r_mat = x.rotation().matrix()
        t = x.translation()
        n_w = pl.normal().point3()
        n_s = r_mat.T @ n_w
        d_s = pl.distance() + n_w @ t
        r = np.concatenate([[sn * (n_s @ c + d_s)], lt @ n_s]) * inv_sigma
        if jac is not None:
            dr_dn = np.vstack([sn * c[None, :], lt]) * inv_sigma
            dr_dd = np.array([sn * inv_sigma, 0, 0, 0])[:, None]
            # GTSAM Pose3 tangent (omega, v), right perturbation.
            dn_dpose = np.hstack([hat(n_s), np.zeros((3, 3))])
            dd_dpose = np.hstack([np.zeros(3), n_s])[None, :]
            b = pl.normal().basis()
            dn_dplane = np.hstack([r_mat.T @ b, np.zeros((3, 1))])
            dd_dplane = np.hstack([t @ b, [1.0]])[None, :]
            jac[0] = dr_dn @ dn_dpose + dr_dd @ dd_dpose
            jac[1] = dr_dn @ dn_dplane + dr_dd @ dd_dplane
        return r

    noise = robust(gtsam.noiseModel.Unit.Create(4), rec.get("robust"))
    return gtsam.CustomFactor(noise, [kx, kp], error)


def build(doc):
    graph = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    for p in doc["poses"]:
        values.insert(gtsam.symbol("x", p["id"]), pose_of(p["t"], p["q"]))
    for p in doc["planes"]:
        n, d = p["n"], p["d"]
        values.insert(gtsam.symbol("p", p["id"]), gtsam.OrientedPlane3(n[0], n[1], n[2], d))
    has_prior = False
    for rec in doc["factors"]:
        kind = rec["type"]
        keys = [key_of(k) for k in rec["keys"]]
        if kind == "pose_prior":
            has_prior = True
            m = rec["measurement"]
            noise = gtsam.noiseModel.Gaussian.SqrtInformation(pose_sqrt_info(rec["sqrt_info"]))
            graph.add(gtsam.PriorFactorPose3(keys[0], pose_of(m["t"], m["q"]),
                                             robust(noise, rec.get("robust"))))
        elif kind == "between":
            m = rec["measurement"]
            noise = gtsam.noiseModel.Gaussian.SqrtInformation(pose_sqrt_info(rec["sqrt_info"]))
            graph.add(gtsam.BetweenFactorPose3(keys[0], keys[1], pose_of(m["t"], m["q"]),
                                               robust(noise, rec.get("robust"))))
        elif kind == "plane_observation":
            m = rec["measurement"]
            s = np.asarray(rec["sqrt_info"], dtype=float).reshape(3, 3)
            noise = robust(gtsam.noiseModel.Gaussian.SqrtInformation(s), rec.get("robust"))
            z = np.array([m["n"][0], m["n"][1], m["n"][2], m["d"]])
            graph.add(gtsam.OrientedPlane3Factor(z, noise, keys[0], keys[1]))
        elif kind == "point_to_plane":
            graph.add(point_to_plane_factor(rec))
        else:
            raise ValueError(f"unknown factor type {kind}")
    # Gauge, as specular: the listed fixed keys, plus the first pose when
    # auto_gauge is on and nothing else anchors it.
    fixed = list(doc.get("fixed", []))
    if any(k.startswith("p") for k in fixed):
        raise ValueError("fixed planes are not supported by this script")
    if doc.get("auto_gauge", True) and not has_prior and not fixed and doc["poses"]:
        fixed = ["x%d" % min(p["id"] for p in doc["poses"])]
    tight = gtsam.noiseModel.Isotropic.Sigma(6, 1e-9)
    for k in fixed:
        key = key_of(k)
        graph.add(gtsam.PriorFactorPose3(key, values.atPose3(key), tight))
    return graph, values


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("graph")
    ap.add_argument("--optimizer", choices=["gn", "lm"], default="gn")
    ap.add_argument("--max-iterations", type=int, default=100)
    ap.add_argument("--tolerance", type=float, default=1e-5)
    args = ap.parse_args()
    try:
        with open(args.graph) as f:
            doc = json.load(f)
        if doc.get("format") != "specular-factor-graph" or doc.get("version") != 1:
            raise ValueError("not a specular-factor-graph version 1 file")
        graph, initial = build(doc)
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as e:
        print(f"{args.graph}: {e}", file=sys.stderr)
        return 2
    if args.optimizer == "gn":
        params = gtsam.GaussNewtonParams()
    else:
        params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(args.max_iterations)
    params.setRelativeErrorTol(args.tolerance)
    params.setAbsoluteErrorTol(args.tolerance)
    if args.optimizer == "gn":
        opt = gtsam.GaussNewtonOptimizer(graph, initial, params)
    else:
        opt = gtsam.LevenbergMarquardtOptimizer(graph, initial, params)
    initial_error = graph.error(initial)
    t0 = time.perf_counter()
    result = opt.optimize()
    seconds = time.perf_counter() - t0
    print(json.dumps({
        "optimizer": args.optimizer,
        "initial_error": initial_error,
        "final_error": graph.error(result),
        "iterations": opt.iterations(),
        "seconds": seconds,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
