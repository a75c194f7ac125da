//! The factrs back-end against ours: the same final cost as `lm` and `gn`
//! on synthetic graphs (both plane factor kinds, with and without robust
//! kernels), and every converted factor's cost equal to ours at random
//! values (free variables and each way of baking fixed ones in).
//!
//! Run with `cargo test --release --features factrs --test backend_factrs`.
#![cfg(feature = "factrs")]

use std::collections::BTreeSet;

use nalgebra::{Isometry3, Matrix6, Vector3, Vector6};
use specular::backend::factors::Factor;
use specular::backend::factrs_adapter::{converted_costs, from_se3, to_se3, Factrs, FactrsMethod};
use specular::backend::synthetic::{synthetic, SyntheticParams};
use specular::backend::{
    backend, gauss_newton, levenberg_marquardt, AnyFactor, Backend, BackendName, BackendParams,
    FactorGraph, Key, PlaneFactorKind, PosePrior, RobustKernel, SolverParams, Values,
};
use specular::geometry::se3;
use specular::rng::SplitMix64;

fn graph(kind: PlaneFactorKind, seed: u64) -> FactorGraph {
    synthetic(&SyntheticParams {
        poses: 30,
        observations_per_pose: 6,
        factor: kind,
        seed,
        ..SyntheticParams::default()
    })
    .unwrap()
    .graph
}

/// Put `kernel` on every plane factor.
fn robustify(g: &mut FactorGraph, kernel: RobustKernel) {
    for f in &mut g.factors {
        if f.factor.is_plane_factor() {
            f.robust = kernel;
        }
    }
}

fn tight() -> SolverParams {
    SolverParams {
        max_iterations: 200,
        relative_tolerance: 1e-10,
        absolute_tolerance: 1e-12,
        step_tolerance: 1e-14,
        ..SolverParams::default()
    }
}

/// factrs, lm and gn from the same start reach the same cost.
fn same_minimum(g: &FactorGraph) {
    let p = tight();
    let init = g.values.clone();
    let (_, lm) = levenberg_marquardt(g, &init, &p).unwrap();
    let (_, gn) = gauss_newton(g, &init, &p).unwrap();
    let (fv, fr) = Factrs {
        params: p,
        ..Factrs::default()
    }
    .optimize(g, &init)
    .unwrap();
    assert_eq!(fr.solver, "factrs");
    assert!(fr.iterations >= 1, "factrs took no step");
    assert!(
        (fr.initial_cost - lm.initial_cost).abs() <= 1e-12 * lm.initial_cost,
        "initial costs differ: {} vs {}",
        fr.initial_cost,
        lm.initial_cost
    );
    assert!(
        fr.final_cost < 0.5 * fr.initial_cost,
        "factrs did not descend: {fr:?}"
    );
    // The report's final cost is ours at the returned values.
    assert_eq!(fr.final_cost, g.cost(&fv).unwrap());
    eprintln!(
        "initial {:.6}, final factrs {:.9} ({} it), lm {:.9} ({} it), gn {:.9} ({} it)",
        fr.initial_cost,
        fr.final_cost,
        fr.iterations,
        lm.final_cost,
        lm.iterations,
        gn.final_cost,
        gn.iterations
    );
    let (_, fgn) = Factrs {
        params: p,
        method: FactrsMethod::GaussNewton,
    }
    .optimize(g, &init)
    .unwrap();
    for (name, other) in [
        ("lm", lm.final_cost),
        ("gn", gn.final_cost),
        ("factrs gn", fgn.final_cost),
    ] {
        let rel = (fr.final_cost - other).abs() / other;
        assert!(
            rel < 1e-4,
            "factrs final cost {} vs {name} {other} (relative {rel:e})",
            fr.final_cost
        );
    }
    // The gauge pose stayed where it was.
    let first = *g.values.poses.keys().next().unwrap();
    assert_eq!(fv.poses[&first], init.poses[&first]);
}

#[test]
fn factrs_matches_lm_and_gn_plane_to_plane() {
    same_minimum(&graph(PlaneFactorKind::PlaneToPlane, 3));
}

#[test]
fn factrs_matches_lm_and_gn_point_to_plane() {
    same_minimum(&graph(PlaneFactorKind::PointToPlane, 4));
}

#[test]
fn factrs_matches_lm_and_gn_with_robust_kernels() {
    let mut g = graph(PlaneFactorKind::PlaneToPlane, 5);
    robustify(&mut g, RobustKernel::Huber { k: 1.345 });
    same_minimum(&g);
    let mut g = graph(PlaneFactorKind::PointToPlane, 6);
    robustify(&mut g, RobustKernel::Cauchy { k: 2.0 });
    same_minimum(&g);
}

/// A random pose near `x`.
fn jitter(x: &Isometry3<f64>, rng: &mut SplitMix64, t: f64, r: f64) -> Isometry3<f64> {
    let d = Vector6::from_fn(|i, _| rng.normal() * if i < 3 { t } else { r });
    x * se3::exp(&d)
}

/// Values far from the optimum (large residuals, robust kernels active).
fn random_values(g: &FactorGraph, seed: u64) -> Values {
    let mut rng = SplitMix64::new(seed);
    let mut v = g.values.clone();
    for x in v.poses.values_mut() {
        *x = jitter(x, &mut rng, 0.3, 0.2);
    }
    for p in v.planes.values_mut() {
        *p = p.retract(&Vector3::new(
            rng.normal() * 0.2,
            rng.normal() * 0.2,
            rng.normal() * 0.3,
        ));
    }
    v
}

/// Our per-factor cost and factrs' agree (relative 1e-9) for every factor
/// that was converted, and exactly the all-fixed factors were left out.
fn costs_agree(g: &FactorGraph, v: &Values, fixed: &BTreeSet<Key>) {
    let theirs = converted_costs(g, v, fixed).unwrap();
    assert_eq!(theirs.len(), g.factors.len());
    let mut compared = 0;
    for (i, (f, c)) in g.factors.iter().zip(&theirs).enumerate() {
        let all_fixed = f.factor.keys().iter().all(|k| fixed.contains(k));
        match c {
            None => assert!(all_fixed, "factor {i} was dropped"),
            Some(c) => {
                assert!(!all_fixed, "factor {i} should have been dropped");
                let ours = f.cost(v).unwrap();
                assert!(
                    (c - ours).abs() <= 1e-9 * ours.max(1e-12),
                    "factor {i} ({}, {:?}): factrs {c} vs ours {ours}",
                    f.factor.type_name(),
                    f.robust
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 0);
}

/// A graph with every factor kind: plane-to-plane and point-to-plane
/// observations, betweens, a pose prior, and all three kernels.
fn mixed_graph() -> FactorGraph {
    let mut g = graph(PlaneFactorKind::PlaneToPlane, 7);
    let p2p = graph(PlaneFactorKind::PointToPlane, 7);
    // Same poses and planes (same seed): take its point-to-plane factors.
    g.factors.extend(
        p2p.factors
            .into_iter()
            .filter(|f| f.factor.is_plane_factor()),
    );
    let mut s = Matrix6::identity() * 10.0;
    s[(0, 4)] = 2.0; // a non-diagonal square-root information
    s[(5, 1)] = -3.0;
    g.add(AnyFactor::PosePrior(PosePrior::new(
        2,
        g.values.poses[&2] * se3::exp(&Vector6::new(0.1, 0.0, -0.2, 0.05, 0.0, 0.1)),
        s,
    )));
    for (i, f) in g.factors.iter_mut().enumerate() {
        f.robust = match i % 3 {
            0 => RobustKernel::None,
            1 => RobustKernel::Huber { k: 1.345 },
            _ => RobustKernel::Cauchy { k: 2.3849 },
        };
    }
    g
}

#[test]
fn converted_residuals_cost_the_same_as_ours() {
    let g = mixed_graph();
    for seed in 0..5 {
        let v = random_values(&g, 100 + seed);
        // Everything free: the two-variable residuals.
        costs_agree(&g, &v, &BTreeSet::new());
        // Some poses and planes fixed: the baked-in one-variable residuals
        // (first or second pose of a between, pose or plane of a plane
        // factor, both).
        let fixed: BTreeSet<Key> = [
            Key::Pose(0),
            Key::Pose(5),
            Key::Pose(6),
            Key::Plane(1),
            Key::Plane(4),
        ]
        .into_iter()
        .collect();
        costs_agree(&g, &v, &fixed);
    }
}

#[test]
fn pose_conversion_round_trips() {
    let mut rng = SplitMix64::new(9);
    for _ in 0..20 {
        let x = jitter(&Isometry3::identity(), &mut rng, 5.0, 1.0);
        let back = from_se3(&to_se3(&x));
        assert!((back.translation.vector - x.translation.vector).norm() < 1e-12);
        assert!(back.rotation.angle_to(&x.rotation) < 1e-12);
    }
}

#[test]
fn selected_by_name_and_bad_input_is_an_error() {
    let params = BackendParams::default();
    let b = backend(BackendName::Factrs, &params).unwrap();
    assert_eq!(b.name(), "factrs");
    let g = graph(PlaneFactorKind::PointToPlane, 8);
    // Initial values lacking a variable: a typed error, not a panic.
    let mut missing = g.values.clone();
    let last = *missing.poses.keys().last().unwrap();
    missing.poses.remove(&last);
    assert!(b.optimize(&g, &missing).is_err());
    // Non-finite initial values.
    let mut nan = g.values.clone();
    nan.planes.values_mut().next().unwrap().d = f64::NAN;
    assert!(b.optimize(&g, &nan).is_err());
}

#[test]
fn deterministic() {
    let g = graph(PlaneFactorKind::PlaneToPlane, 10);
    let b = Factrs::default();
    let (v1, r1) = b.optimize(&g, &g.values).unwrap();
    let (v2, r2) = b.optimize(&g, &g.values).unwrap();
    assert_eq!(v1, v2);
    assert_eq!(r1.final_cost, r2.final_cost);
    assert_eq!(r1.iterations, r2.iterations);
}

/// factrs' autodiff Jacobians of the converted residuals equal our analytic
/// ones once the conventions are mapped: pose columns `(ω, v)` ↔ `(ρ, φ)`,
/// pose-factor residuals negated.
#[test]
fn converted_jacobians_match_our_analytic_ones() {
    use specular::backend::factors::Linearization;
    use specular::backend::factrs_adapter::converted_linearizations;
    let g = mixed_graph();
    let fixed: BTreeSet<Key> = [Key::Pose(0), Key::Plane(3)].into_iter().collect();
    let mut checked = [0usize; 4];
    for seed in 0..3 {
        let v = random_values(&g, 200 + seed);
        let theirs = converted_linearizations(&g, &v, &fixed).unwrap();
        let mut lin = Linearization::default();
        for (i, (f, t)) in g.factors.iter().zip(&theirs).enumerate() {
            let Some(t) = t else { continue };
            f.linearize(&v, &mut lin).unwrap();
            let sign = if f.factor.is_plane_factor() {
                1.0
            } else {
                -1.0
            };
            assert_eq!(t.residual.len(), lin.dim, "factor {i}");
            let scale = 1.0 + lin.residual.amax();
            for r in 0..lin.dim {
                let d = (t.residual[r] - sign * lin.residual[r]).abs();
                assert!(d <= 1e-9 * scale, "factor {i} residual row {r}: {d:e}");
            }
            // Our column for each of factrs' columns.
            let mut cols = Vec::new();
            for (b, key) in f.factor.keys().iter().enumerate() {
                if !t.keys.contains(key) {
                    continue;
                }
                match key {
                    Key::Pose(_) => cols.extend((0..6).map(|k| (b, (k + 3) % 6))),
                    Key::Plane(_) => cols.extend((0..3).map(|k| (b, k))),
                }
            }
            let jmax = lin
                .jacobians
                .iter()
                .map(|j| j.rows(0, lin.dim).amax())
                .fold(0.0, f64::max);
            for r in 0..lin.dim {
                assert_eq!(t.jacobian[r].len(), cols.len(), "factor {i}");
                for (c, &(b, k)) in cols.iter().enumerate() {
                    let ours = sign * lin.jacobians[b][(r, k)];
                    let d = (t.jacobian[r][c] - ours).abs();
                    assert!(
                        d <= 1e-7 * (1.0 + jmax),
                        "factor {i} ({}) J[{r},{c}]: factrs {} vs ours {ours}",
                        f.factor.type_name(),
                        t.jacobian[r][c]
                    );
                }
            }
            let kind = match f.factor {
                AnyFactor::PosePrior(_) => 0,
                AnyFactor::Between(_) => 1,
                AnyFactor::PlaneObservation(_) => 2,
                AnyFactor::PointToPlane(_) => 3,
            };
            checked[kind] += 1;
        }
    }
    assert!(checked.iter().all(|&n| n > 0), "kinds checked: {checked:?}");
}

#[test]
fn nothing_free_returns_the_initial_values() {
    let mut g = graph(PlaneFactorKind::PlaneToPlane, 11);
    g.fixed = g.values.keys().collect();
    let (v, r) = Factrs::default().optimize(&g, &g.values).unwrap();
    assert_eq!(v, g.values);
    assert_eq!(r.iterations, 0);
    assert_eq!(r.final_cost, r.initial_cost);
}
