//! Integration tests of the back-end: the sparse solvers against the dense
//! reference, accuracy against ground truth, robust kernels, the file format
//! and clear errors on singular or malformed problems.

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Matrix6, Translation3, UnitQuaternion, Vector3};
use specular::backend::dense::dense_gauss_newton;
use specular::backend::synthetic::{mean_translation_error, synthetic, SyntheticParams};
use specular::backend::{
    backend, gauss_newton, levenberg_marquardt, AnyFactor, BackendName, BackendParams, Between,
    FactorGraph, GraphFactor, Key, PlaneFactorKind, PlaneObservation, PlaneVar, RobustKernel,
    SolverParams,
};
use specular::geometry::Plane;

fn tight() -> SolverParams {
    SolverParams {
        max_iterations: 50,
        relative_tolerance: 1e-12,
        absolute_tolerance: 1e-12,
        step_tolerance: 1e-12,
        ..SolverParams::default()
    }
}

fn small(seed: u64, factor: PlaneFactorKind) -> specular::backend::synthetic::SyntheticGraph {
    synthetic(&SyntheticParams {
        poses: 30,
        seed,
        factor,
        ..SyntheticParams::default()
    })
    .unwrap()
}

#[test]
fn sparse_solvers_reach_the_dense_reference_cost() {
    for seed in 1..=4 {
        for factor in [PlaneFactorKind::PlaneToPlane, PlaneFactorKind::PointToPlane] {
            let s = small(seed, factor);
            let g = &s.graph;
            let (_, dense) = dense_gauss_newton(g, &g.values, &tight()).unwrap();
            let (_, gn) = gauss_newton(g, &g.values, &tight()).unwrap();
            let (_, lm) = levenberg_marquardt(g, &g.values, &tight()).unwrap();
            assert!(dense.final_cost < 0.1 * dense.initial_cost, "{dense:?}");
            for r in [&gn, &lm] {
                let rel = (r.final_cost - dense.final_cost).abs() / dense.final_cost;
                assert!(
                    rel < 1e-6,
                    "seed {seed} {factor:?} {}: {} vs dense {}",
                    r.solver,
                    r.final_cost,
                    dense.final_cost
                );
                assert_eq!(r.initial_cost, dense.initial_cost);
                assert!(r.converged, "{:?}", r.termination);
            }
        }
    }
}

#[test]
fn optimisation_reduces_the_pose_error() {
    for factor in [PlaneFactorKind::PlaneToPlane, PlaneFactorKind::PointToPlane] {
        let s = synthetic(&SyntheticParams {
            poses: 200,
            seed: 7,
            factor,
            ..SyntheticParams::default()
        })
        .unwrap();
        let before = mean_translation_error(&s.graph.values, &s.truth);
        for name in [BackendName::Gn, BackendName::Lm] {
            let b = backend(name, &BackendParams::default()).unwrap();
            let (out, report) = b.optimize(&s.graph, &s.graph.values).unwrap();
            let after = mean_translation_error(&out, &s.truth);
            assert!(
                after < 0.3 * before && after < 0.1,
                "{factor:?} {}: {before} -> {after} ({report:?})",
                b.name()
            );
            assert!(report.observability.weak.is_empty());
        }
    }
}

#[test]
fn results_are_deterministic() {
    let s = small(3, PlaneFactorKind::PointToPlane);
    let (a, ra) = levenberg_marquardt(&s.graph, &s.graph.values, &tight()).unwrap();
    let (b, rb) = levenberg_marquardt(&s.graph, &s.graph.values, &tight()).unwrap();
    assert_eq!(a, b);
    assert_eq!(ra.final_cost.to_bits(), rb.final_cost.to_bits());
}

#[test]
fn robust_kernels_limit_a_gross_outlier() {
    let s = small(5, PlaneFactorKind::PlaneToPlane);
    let clean = {
        let (v, _) = gauss_newton(&s.graph, &s.graph.values, &tight()).unwrap();
        mean_translation_error(&v, &s.truth)
    };
    let error_with = |kernel: RobustKernel| {
        let mut g = s.graph.clone();
        // A confident loop closure claiming poses 5 and 25 are 30 m apart.
        let wrong = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 30.0),
            UnitQuaternion::identity(),
        );
        let info = Matrix6::identity() * 100.0;
        g.factors
            .push(GraphFactor::new(AnyFactor::Between(Between::new(
                5, 25, wrong, info,
            ))));
        for f in &mut g.factors {
            f.robust = kernel;
        }
        let (v, _) = levenberg_marquardt(&g, &g.values, &tight()).unwrap();
        mean_translation_error(&v, &s.truth)
    };
    let plain = error_with(RobustKernel::None);
    let huber = error_with(RobustKernel::Huber { k: 1.345 });
    let cauchy = error_with(RobustKernel::Cauchy { k: 1.0 });
    assert!(
        plain > 10.0 * clean,
        "outlier should hurt least squares: {plain} vs {clean}"
    );
    assert!(huber < 0.5 * plain, "huber {huber} vs plain {plain}");
    assert!(
        cauchy < 3.0 * clean + 0.01,
        "cauchy {cauchy} vs clean {clean}"
    );
}

#[test]
fn json_round_trip_keeps_the_cost() {
    let dir = tempfile::tempdir().unwrap();
    for factor in [PlaneFactorKind::PlaneToPlane, PlaneFactorKind::PointToPlane] {
        let mut s = small(2, factor);
        s.graph.factors[3].robust = RobustKernel::Cauchy { k: 2.0 };
        s.graph.fixed.insert(Key::Plane(0));
        let path = dir.path().join("g.json");
        s.graph.write(&path).unwrap();
        let back = FactorGraph::read(&path).unwrap();
        assert_eq!(back.factors.len(), s.graph.factors.len());
        assert_eq!(back.fixed, s.graph.fixed);
        assert_eq!(back.factors[3].robust, RobustKernel::Cauchy { k: 2.0 });
        let a = s.graph.cost(&s.graph.values).unwrap();
        let b = back.cost(&back.values).unwrap();
        assert!((a - b).abs() <= 1e-12 * a, "{a} vs {b}");
        assert_eq!(back.values, s.graph.values);
    }
}

fn error_text(path: &Path, text: &str) -> String {
    std::fs::write(path, text).unwrap();
    FactorGraph::read(path).unwrap_err().to_string()
}

#[test]
fn malformed_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.json");
    small(1, PlaneFactorKind::PlaneToPlane)
        .graph
        .write(&good)
        .unwrap();
    let text = std::fs::read_to_string(&good).unwrap();
    let bad = dir.path().join("bad.json");
    let cases = [
        ("truncated", text[..text.len() / 2].to_string()),
        ("not json", "hello".to_string()),
        (
            "unknown field",
            text.replacen("\"version\"", "\"colour\":1,\"version\"", 1),
        ),
        (
            "wrong version",
            text.replacen("\"version\":1", "\"version\":9", 1),
        ),
        (
            "unknown variable",
            text.replacen("\"keys\":[\"x0\",\"x1\"]", "\"keys\":[\"x0\",\"x999\"]", 1),
        ),
        (
            "bad key",
            text.replacen("\"keys\":[\"x0\",\"x1\"]", "\"keys\":[\"x0\",\"q1\"]", 1),
        ),
        (
            "bad sqrt_info",
            text.replacen("\"sqrt_info\":[", "\"sqrt_info\":[1.0,", 1),
        ),
        ("nan", text.replacen("\"d\":", "\"d\":NaN,\"e\":", 1)),
    ];
    for (what, content) in cases {
        assert_ne!(content, text, "{what}: the edit did not apply");
        let msg = error_text(&bad, &content);
        assert!(msg.contains("bad.json"), "{what}: {msg}");
    }
    let missing = FactorGraph::read(&dir.path().join("nope.json")).unwrap_err();
    assert!(missing.to_string().contains("nope.json"));
}

#[test]
fn singular_problems_are_clear_errors() {
    // A plane nobody observes.
    let mut s = small(1, PlaneFactorKind::PlaneToPlane);
    s.graph.values.planes.insert(
        999,
        PlaneVar {
            normal: Vector3::z(),
            d: 3.0,
        },
    );
    for b in [BackendName::Gn, BackendName::Lm] {
        let err = backend(b, &BackendParams::default())
            .unwrap()
            .optimize(&s.graph, &s.graph.values)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("p999") && err.contains("no information"),
            "{err}"
        );
    }
    // Gauge freedom.
    let mut s = small(1, PlaneFactorKind::PlaneToPlane);
    s.graph.auto_gauge = false;
    let err = gauss_newton(&s.graph, &s.graph.values, &tight())
        .unwrap_err()
        .to_string();
    assert!(err.contains("gauge"), "{err}");
    // Missing initial values.
    let s = small(1, PlaneFactorKind::PlaneToPlane);
    let mut partial = s.graph.values.clone();
    partial.poses.remove(&3);
    let err = gauss_newton(&s.graph, &partial, &tight())
        .unwrap_err()
        .to_string();
    assert!(err.contains("x3"), "{err}");
    // factrs is not built (without the cargo feature).
    if !cfg!(feature = "factrs") {
        let err = backend(BackendName::Factrs, &BackendParams::default())
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("--features factrs"), "{err}");
    }
}

/// A corridor: two walls (normals ±y) and a floor; odometry along x. The
/// walls and floor leave translation along x unobservable: the report says
/// so for every pose, with the weakest direction along ρ_x.
#[test]
fn corridor_axis_is_reported() {
    // The corridor runs at 30° from x, so no variable is exactly free and
    // the singular direction must be found numerically.
    let yaw = UnitQuaternion::from_scaled_axis(Vector3::z() * std::f64::consts::FRAC_PI_6);
    let axis = yaw * Vector3::x();
    let side = yaw * Vector3::y();
    let mut g = FactorGraph::new();
    let planes = [
        Plane {
            normal: side,
            d: 2.0,
        },
        Plane {
            normal: -side,
            d: 2.0,
        },
        Plane {
            normal: Vector3::z(),
            d: 1.5,
        },
    ];
    for (j, p) in planes.iter().enumerate() {
        g.values.planes.insert(j as u32, PlaneVar::from(*p));
    }
    // The sensor is yawed 0.3 rad off the corridor: in its frame the free
    // direction mixes x and y.
    let heading = yaw * UnitQuaternion::from_scaled_axis(Vector3::z() * 0.3);
    let truth = |i: u32| Isometry3::from_parts(Translation3::from(axis * i as f64), heading);
    for i in 0..10u32 {
        let x = truth(i);
        // Start off the truth so the solver has work to do.
        let start = Isometry3::from_parts(
            Translation3::from(x.translation.vector + side * 0.05 * (i % 3) as f64),
            x.rotation,
        );
        g.values.poses.insert(i, start);
        if i > 0 {
            let z = truth(i - 1).inverse() * x;
            g.add(AnyFactor::Between(Between::new(
                i - 1,
                i,
                z,
                Matrix6::identity() * 10.0,
            )));
        }
        for (j, p) in planes.iter().enumerate() {
            let meas = p.transformed(&x.inverse());
            g.add(AnyFactor::PlaneObservation(PlaneObservation::new(
                i,
                j as u32,
                meas,
                Matrix3::identity() * 100.0,
            )));
        }
    }
    let (_, report) = levenberg_marquardt(&g, &g.values, &tight()).unwrap();
    let weak = &report.observability.weak;
    assert!(
        report.final_cost < 1e-12 * report.initial_cost.max(1.0) + 1e-12,
        "{report:?}"
    );
    assert_eq!(weak.len(), 10, "{:?}", report.observability);
    for w in weak {
        assert_eq!(w.directions, 1, "{w:?}");
        // ρ is in the sensor frame: the corridor axis seen from the sensor.
        let expect = heading.inverse() * axis;
        let v = Vector3::new(
            w.weakest_direction[0],
            w.weakest_direction[1],
            w.weakest_direction[2],
        );
        assert!(v.dot(&expect).abs() > 0.999, "{w:?} vs {expect}");
    }
    // Without odometry, GN refuses with a clear error instead of a wrong pose.
    g.factors.retain(|f| f.factor.is_plane_factor());
    match gauss_newton(&g, &g.values, &tight()) {
        Err(e) => assert!(e.to_string().contains("not positive definite"), "{e}"),
        Ok((_, r)) => panic!("corridor without odometry solved silently: {r:?}"),
    }
}

#[test]
fn average_backend_keeps_poses_and_moves_planes() {
    let s = small(4, PlaneFactorKind::PlaneToPlane);
    let b = backend(BackendName::Average, &BackendParams::default()).unwrap();
    let (out, report) = b.optimize(&s.graph, &s.graph.values).unwrap();
    assert_eq!(out.poses, s.graph.values.poses);
    assert_ne!(out.planes, s.graph.values.planes);
    assert_eq!(report.iterations, 0);
}

#[test]
fn backend_params_parse_as_a_toml_section() {
    // A complete section, as a configuration file layered over a built-in
    // gives it (the defaults are configs/default.toml's, not the struct's).
    let toml::Value::Table(mut section) = toml::Value::try_from(BackendParams::default()).unwrap()
    else {
        panic!("a table");
    };
    section.insert("name".into(), "gn".into());
    section.insert(
        "robust".into(),
        toml::Value::Table(toml::from_str("kind = \"huber\"\nk = 2.0").unwrap()),
    );
    section["solver"]
        .as_table_mut()
        .unwrap()
        .insert("relative_tolerance".into(), 1e-7.into());
    let p: BackendParams = toml::Value::Table(section.clone()).try_into().unwrap();
    assert_eq!(p.name, BackendName::Gn);
    assert_eq!(p.solver.relative_tolerance, 1e-7);
    assert_eq!(p.robust, RobustKernel::Huber { k: 2.0 });
    let with = |key: &str, value: toml::Value| {
        let mut s = section.clone();
        s.insert(key.into(), value);
        toml::Value::Table(s).try_into::<BackendParams>()
    };
    assert!(with("nmae", "gn".into()).is_err());
    assert!(with("name", "ceres".into()).is_err());
    // The iteration cap is a constant now, no key.
    let mut s = section.clone();
    s["solver"]
        .as_table_mut()
        .unwrap()
        .insert("max_iterations".into(), 7.into());
    assert!(toml::Value::Table(s).try_into::<BackendParams>().is_err());
}
