//! Property tests of the back-end's calculus: every factor's analytic
//! Jacobian against central differences (w.r.t. every variable, through the
//! variables' own retractions), retract/local round trips, the SE(3) right
//! Jacobian, GTSAM's `Unit3` local coordinates and the robust kernels'
//! derivatives.

use std::f64::consts::PI;

use nalgebra::{
    DMatrix, Isometry3, Matrix3, Matrix6, Translation3, UnitQuaternion, Vector2, Vector3, Vector6,
};
use proptest::prelude::*;
use specular::backend::factors::{AnyFactor, Factor};
use specular::backend::unit3;
use specular::backend::{
    Between, Key, PlaneObservation, PlaneVar, PointToPlane, PosePrior, RobustKernel, Values,
};
use specular::geometry::{se3, Plane};

// ---------------------------------------------------------------- strategies

fn vec3(r: f64) -> impl Strategy<Value = Vector3<f64>> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// A rotation vector with angle in `[0, max)`.
fn rotvec(max: f64) -> impl Strategy<Value = Vector3<f64>> {
    (-1.0..1.0f64, 0.0..2.0 * PI, 0.0..max).prop_map(|(z, az, a)| {
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * az.cos(), r * az.sin(), z) * a
    })
}

fn isometry() -> impl Strategy<Value = Isometry3<f64>> {
    (vec3(10.0), rotvec(PI - 0.1)).prop_map(|(t, w)| {
        Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(w))
    })
}

fn twist(t: f64, r: f64) -> impl Strategy<Value = Vector6<f64>> {
    (vec3(t), rotvec(r)).prop_map(|(a, b)| Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z))
}

fn unit() -> impl Strategy<Value = Vector3<f64>> {
    vec3(1.0).prop_filter_map("short", |v| v.try_normalize(0.1))
}

fn plane_var() -> impl Strategy<Value = PlaneVar> {
    (unit(), 0.1..40.0f64).prop_map(|(n, d)| PlaneVar { normal: n, d })
}

/// An upper-triangular square-root information with a positive diagonal.
fn sqrt_info<const N: usize>() -> impl Strategy<Value = nalgebra::SMatrix<f64, N, N>> {
    prop::collection::vec(-1.0..1.0f64, N * N).prop_map(|v| {
        let mut m = nalgebra::SMatrix::<f64, N, N>::from_row_slice(&v);
        for r in 0..N {
            for c in 0..r {
                m[(r, c)] = 0.0;
            }
            m[(r, r)] = 0.5 + m[(r, r)].abs() * 5.0;
        }
        m
    })
}

/// Whether GTSAM's basis axis choice is unambiguous at `p` (central
/// differences straddling an axis switch measure a discontinuity).
fn clear_axis(p: &Vector3<f64>) -> bool {
    let mut a = [p.x.abs(), p.y.abs(), p.z.abs()];
    a.sort_by(|x, y| x.partial_cmp(y).unwrap());
    a[1] - a[0] > 1e-3
}

// ------------------------------------------------------------------- helpers

/// Compare the factor's analytic Jacobians with central differences taken
/// through `Values::retract_key` for every key.
fn check_jacobians(factor: &dyn Factor, values: &Values) -> Result<(), TestCaseError> {
    let mut analytic = [Matrix6::zeros(); 2];
    factor.evaluate(values, Some(&mut analytic)).unwrap();
    let m = factor.dim();
    let h = 1e-6;
    for (k, &key) in factor.keys().iter().enumerate() {
        let mut numeric = DMatrix::zeros(m, key.dim());
        for i in 0..key.dim() {
            let mut e = vec![0.0; key.dim()];
            e[i] = h;
            let mut plus = values.clone();
            plus.retract_key(key, &e).unwrap();
            e[i] = -h;
            let mut minus = values.clone();
            minus.retract_key(key, &e).unwrap();
            let rp = factor.evaluate(&plus, None).unwrap();
            let rm = factor.evaluate(&minus, None).unwrap();
            for r in 0..m {
                numeric[(r, i)] = (rp[r] - rm[r]) / (2.0 * h);
            }
        }
        let a = analytic[k].view((0, 0), (m, key.dim())).into_owned();
        let err = (&a - &numeric).abs().max();
        let scale = 1.0 + numeric.abs().max();
        prop_assert!(
            err < 2e-5 * scale,
            "key {key}: analytic {a} numeric {numeric} (err {err})"
        );
    }
    Ok(())
}

fn values_with(poses: &[Isometry3<f64>], planes: &[PlaneVar]) -> Values {
    let mut v = Values::default();
    for (i, x) in poses.iter().enumerate() {
        v.poses.insert(i as u32, *x);
    }
    for (i, p) in planes.iter().enumerate() {
        v.planes.insert(i as u32, *p);
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    // ------------------------------------------------------------ manifolds

    #[test]
    fn pose_retract_local_round_trip(x in isometry(), d in twist(3.0, 2.5)) {
        let y = se3::retract(&x, &d);
        let back = se3::local(&x, &y);
        prop_assert!((back - d).norm() < 1e-9 * (1.0 + d.norm()), "{back} vs {d}");
    }

    #[test]
    fn plane_retract_local_round_trip(p in plane_var(), v in vec3(1.5)) {
        let q = p.retract(&v);
        prop_assert!((q.normal.norm() - 1.0).abs() < 1e-14);
        let back = p.local(&q);
        prop_assert!((back - v).norm() < 1e-9, "{back} vs {v}");
        // and local then retract returns the other plane
        let r = p.retract(&p.local(&q));
        prop_assert!((r.normal - q.normal).norm() < 1e-9 && (r.d - q.d).abs() < 1e-12);
    }

    #[test]
    fn se3_right_jacobian_inverse_matches_differences(xi in twist(5.0, 2.8)) {
        let x = se3::exp(&xi);
        let analytic = se3::se3_right_jacobian_inv(&xi);
        let h = 1e-6;
        let mut numeric = Matrix6::zeros();
        for i in 0..6 {
            let mut d = Vector6::zeros();
            d[i] = h;
            let p = se3::log(&se3::retract(&x, &d));
            let m = se3::log(&se3::retract(&x, &-d));
            numeric.set_column(i, &((p - m) / (2.0 * h)));
        }
        prop_assert!((analytic - numeric).abs().max() < 1e-5 * (1.0 + numeric.abs().max()),
            "analytic {analytic} numeric {numeric}");
        // J_l of SE(3) is the inverse of J_l⁻¹(ξ) = J_r⁻¹(−ξ).
        let jl = se3::se3_left_jacobian(&xi);
        let prod = jl * se3::se3_right_jacobian_inv(&-xi);
        prop_assert!((prod - Matrix6::identity()).abs().max() < 1e-9);
    }

    #[test]
    fn unit3_local_jacobian_matches_differences(p in unit(), v in vec3(1.2)) {
        prop_assume!(clear_axis(&p));
        let q = unit3::retract(&p, &Vector2::new(v.x, v.y));
        let (_, jac) = unit3::local_coordinates_with_jacobian(&p, &q);
        let b = unit3::basis(&p);
        let h = 1e-6;
        for i in 0..2 {
            let mut e = Vector2::zeros();
            e[i] = h;
            let lp = unit3::local_coordinates(&unit3::retract(&p, &e), &q);
            let lm = unit3::local_coordinates(&unit3::retract(&p, &-e), &q);
            let numeric = (lp - lm) / (2.0 * h);
            let analytic = jac * b.column(i);
            prop_assert!((analytic - numeric).norm() < 1e-6 * (1.0 + numeric.norm()),
                "dir {i}: {analytic} vs {numeric}");
        }
    }

    #[test]
    fn unit3_error_vector_jacobian_matches_differences(p in unit(), q in unit()) {
        prop_assume!(clear_axis(&p));
        let (e, jac) = unit3::error_vector_with_jacobian(&p, &q);
        // Bᵀ q: norm sin θ.
        let sin = p.cross(&q).norm();
        prop_assert!((e.norm() - sin).abs() < 1e-12);
        let b = unit3::basis(&p);
        let h = 1e-6;
        for i in 0..2 {
            let mut d = Vector2::zeros();
            d[i] = h;
            let ep = unit3::error_vector_with_jacobian(&unit3::retract(&p, &d), &q).0;
            let em = unit3::error_vector_with_jacobian(&unit3::retract(&p, &-d), &q).0;
            let numeric = (ep - em) / (2.0 * h);
            let analytic = jac * b.column(i);
            prop_assert!((analytic - numeric).norm() < 1e-6 * (1.0 + numeric.norm()),
                "dir {i}: {analytic} vs {numeric}");
        }
    }

    // -------------------------------------------------------------- factors

    #[test]
    fn pose_prior_jacobian(x in isometry(), noise in twist(2.0, 2.0), s in sqrt_info::<6>()) {
        let prior = x * se3::exp(&noise);
        let f = AnyFactor::PosePrior(PosePrior::new(0, prior, s));
        check_jacobians(&f, &values_with(&[x], &[]))?;
    }

    #[test]
    fn between_jacobians(
        a in isometry(), b in isometry(), noise in twist(2.0, 2.0), s in sqrt_info::<6>()
    ) {
        let z = a.inverse() * b * se3::exp(&noise);
        let f = AnyFactor::Between(Between::new(0, 1, z, s));
        check_jacobians(&f, &values_with(&[a, b], &[]))?;
    }

    #[test]
    fn plane_observation_jacobians(
        x in isometry(), p in plane_var(), v in vec3(0.6), s in sqrt_info::<3>()
    ) {
        let predicted = p.plane().transformed(&x.inverse());
        prop_assume!(clear_axis(&predicted.normal));
        let meas = Plane {
            normal: unit3::retract(&predicted.normal, &Vector2::new(v.x, v.y)),
            d: predicted.d + v.z,
        };
        let f = AnyFactor::PlaneObservation(PlaneObservation::new(0, 0, meas, s));
        check_jacobians(&f, &values_with(&[x], &[p]))?;
    }

    #[test]
    fn point_to_plane_jacobians(
        x in isometry(), p in plane_var(),
        pts in prop::collection::vec(vec3(5.0), 3..30), sigma in 0.01..0.2f64
    ) {
        let f = PointToPlane::from_points(0, 0, &pts, sigma).unwrap();
        check_jacobians(&AnyFactor::PointToPlane(f), &values_with(&[x], &[p]))?;
    }

    #[test]
    fn point_to_plane_cost_is_the_sum_of_squared_distances(
        x in isometry(), p in plane_var(),
        pts in prop::collection::vec(vec3(5.0), 1..30), sigma in 0.01..0.2f64
    ) {
        let f = PointToPlane::from_points(0, 0, &pts, sigma).unwrap();
        let values = values_with(&[x], &[p]);
        let r = f.evaluate(&values, None).unwrap();
        let sensor = p.plane().transformed(&x.inverse());
        let direct: f64 = pts.iter().map(|q| (sensor.normal.dot(q) + sensor.d).powi(2)).sum();
        let ours = r.rows(0, 4).norm_squared() * sigma * sigma;
        prop_assert!((ours - direct).abs() < 1e-8 * (1.0 + direct), "{ours} vs {direct}");
    }

    // --------------------------------------------------------------- robust

    #[test]
    fn robust_kernel_derivatives(k in 0.1..5.0f64, s in 1e-3..100.0f64, which in 0..3usize) {
        let kernel = match which {
            0 => RobustKernel::None,
            1 => RobustKernel::Huber { k },
            _ => RobustKernel::Cauchy { k },
        };
        // Stay off Huber's kink at s = k².
        prop_assume!((s - k * k).abs() > 1e-3);
        let h = 1e-6 * (1.0 + s);
        let d1 = (kernel.rho(s + h) - kernel.rho(s - h)) / (2.0 * h);
        let d2 = (kernel.weight(s + h) - kernel.weight(s - h)) / (2.0 * h);
        prop_assert!((kernel.weight(s) - d1).abs() < 1e-6 * (1.0 + d1.abs()));
        prop_assert!((kernel.second_derivative(s) - d2).abs() < 1e-5 * (1.0 + d2.abs()));
        // ρ(s) ≤ s and ρ'(s) ∈ (0, 1]: a kernel only ever down-weights.
        prop_assert!(kernel.rho(s) <= s + 1e-12);
        let w = kernel.weight(s);
        prop_assert!(w > 0.0 && w <= 1.0);
    }
}

#[test]
fn plane_observation_matches_gtsam_error_at_a_hand_computed_case() {
    // Landmark z = 2 seen from a pose translated by (0, 0, 0.5) and rotated
    // 90° about x: in the sensor frame n_s = Rᵀ (0,0,1) = (0,1,0)... check
    // d_s = d_w + n_w·t = 2.5 and zero residual for the exact measurement.
    let x = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.5),
        UnitQuaternion::from_scaled_axis(Vector3::x() * (PI / 2.0)),
    );
    let p = PlaneVar {
        normal: Vector3::z(),
        d: 2.0,
    };
    let exact = p.plane().transformed(&x.inverse());
    assert!((exact.d - 2.5).abs() < 1e-12);
    assert!((exact.normal - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    let f = PlaneObservation::new(0, 0, exact, Matrix3::identity());
    let r = f.evaluate(&values_with(&[x], &[p]), None).unwrap();
    assert!(r.norm() < 1e-12);
    // An offset error of 0.1 m shows up as +0.1 in the third residual.
    let f = PlaneObservation::new(0, 0, Plane { d: 2.4, ..exact }, Matrix3::identity());
    let r = f.evaluate(&values_with(&[x], &[p]), None).unwrap();
    assert!((r[2] - 0.1).abs() < 1e-12 && r.rows(0, 2).norm() < 1e-12);
    assert_eq!(f.keys(), &[Key::Pose(0), Key::Plane(0)]);
}

/// Golden values from GTSAM 4.3 (Python wheel): `OrientedPlane3Factor`
/// `unwhitenedError` and `error` for one pose, landmark, measurement and a
/// non-diagonal square-root information (script in docs/backend.md).
#[test]
fn plane_observation_matches_gtsam_golden_values() {
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        0.8847830922830212,
        0.144193646261696,
        -0.09612909750779734,
        0.432580938785088,
    ));
    let x = Isometry3::from_parts(Translation3::new(1.5, -2.0, 0.7), q);
    let landmark = PlaneVar::new(Vector3::new(0.6, -0.48, 0.64), 12.0).unwrap();
    let meas = Plane {
        normal: Vector3::new(0.1, 0.8, 0.3).normalize(),
        d: 9.5,
    };
    let values = values_with(&[x], &[landmark]);
    let plain = PlaneObservation::new(0, 0, meas, Matrix3::identity());
    let r = plain.evaluate(&values, None).unwrap();
    let gtsam = Vector3::new(0.9291013824427279, -0.18376934688875182, 4.808);
    assert!(
        (r.fixed_rows::<3>(0) - gtsam).norm() < 1e-12,
        "{r} vs {gtsam}"
    );
    let s = Matrix3::new(10.0, 1.0, 0.0, 0.0, 20.0, 2.0, 0.0, 0.0, 5.0);
    let f = PlaneObservation::new(0, 0, meas, s);
    let cost = 0.5 * f.evaluate(&values, None).unwrap().norm_squared();
    assert!((cost - 348.07719276436694).abs() < 1e-9, "{cost}");
}
