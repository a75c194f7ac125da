//! Property tests of the Lie-group identities the back-end and the
//! registration rely on: SO(3) and SE(3) exponential and logarithm, their
//! Jacobians (against central differences), the adjoint, retract and local.

mod common;

use std::f64::consts::PI;

use common::strategies::{iso_close, isometry, rotvec, twist, vec3};
use nalgebra::{Matrix3, Vector3, Vector6};
use proptest::prelude::*;
use specular::geometry::se3;

/// Central-difference Jacobian of `f` at 0.
fn numeric_jacobian(f: impl Fn(&Vector3<f64>) -> Vector3<f64>) -> Matrix3<f64> {
    let h = 1e-6;
    let mut j = Matrix3::zeros();
    for k in 0..3 {
        let mut e = Vector3::zeros();
        e[k] = h;
        j.set_column(k, &((f(&e) - f(&-e)) / (2.0 * h)));
    }
    j
}

proptest! {
    // ---------------------------------------------------------------- SO(3)

    #[test]
    fn so3_log_exp_round_trip(w in rotvec()) {
        let back = se3::so3_log(&se3::so3_exp(&w));
        prop_assert!((back - w).norm() < 1e-9, "{w} -> {back}");
        let back_q = se3::so3_log_quat(&se3::so3_exp_quat(&w));
        prop_assert!((back_q - w).norm() < 1e-9);
    }

    #[test]
    fn so3_exp_is_rotation(w in vec3(10.0)) {
        let r = se3::so3_exp(&w);
        prop_assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
        prop_assert!((r.determinant() - 1.0).abs() < 1e-12);
        let q = se3::so3_exp_quat(&w).to_rotation_matrix().into_inner();
        prop_assert!((q - r).norm() < 1e-12);
    }

    #[test]
    fn so3_log_angle_in_range(w in vec3(10.0)) {
        let r = se3::so3_exp(&w);
        let l = se3::so3_log(&r);
        prop_assert!(l.norm() <= PI + 1e-12);
        prop_assert!((se3::so3_exp(&l) - r).norm() < 1e-9);
    }

    #[test]
    fn left_jacobian_times_inverse(w in rotvec()) {
        let p = se3::so3_left_jacobian(&w) * se3::so3_left_jacobian_inv(&w);
        prop_assert!((p - Matrix3::identity()).norm() < 1e-9);
        let p = se3::so3_left_jacobian_inv(&w) * se3::so3_left_jacobian(&w);
        prop_assert!((p - Matrix3::identity()).norm() < 1e-9);
    }

    #[test]
    fn left_jacobian_matches_numeric(w in rotvec()) {
        let rt = se3::so3_exp(&w).transpose();
        let num = numeric_jacobian(|d| se3::so3_log(&(se3::so3_exp(&(w + d)) * rt)));
        prop_assert!((num - se3::so3_left_jacobian(&w)).norm() < 1e-6, "{num}");
    }

    #[test]
    fn right_jacobian_matches_numeric(w in rotvec()) {
        let rt = se3::so3_exp(&w).transpose();
        let num = numeric_jacobian(|d| se3::so3_log(&(rt * se3::so3_exp(&(w + d)))));
        prop_assert!((num - se3::so3_right_jacobian(&w)).norm() < 1e-6, "{num}");
    }

    #[test]
    fn small_angles_stay_accurate(dir in vec3(1.0), mag in -12.0..-5.0f64, rho in vec3(10.0)) {
        prop_assume!(dir.norm() > 0.1);
        let w = dir.normalize() * 10f64.powf(mag);
        let theta = w.norm();
        // exp against its second-order series (the remainder is O(θ³)).
        let k = se3::hat(&w);
        let series = Matrix3::identity() + k + k * k * 0.5;
        prop_assert!((se3::so3_exp(&w) - series).norm() < 1e-15);
        // log recovers w to full relative precision.
        let back = se3::so3_log(&se3::so3_exp(&w));
        prop_assert!((back - w).norm() < 1e-9 * theta, "{w} -> {back}");
        let back_q = se3::so3_log_quat(&se3::so3_exp_quat(&w));
        prop_assert!((back_q - w).norm() < 1e-12 * theta);
        // Jacobians against their second-order series (remainder O(θ³)).
        let jl = Matrix3::identity() + k * 0.5 + k * k / 6.0;
        prop_assert!((se3::so3_left_jacobian(&w) - jl).norm() < 1e-15);
        let jli = Matrix3::identity() - k * 0.5 + k * k / 12.0;
        prop_assert!((se3::so3_left_jacobian_inv(&w) - jli).norm() < 1e-15);
        // SE(3): t = ρ + ½ φ×ρ + ⅙ φ×(φ×ρ) + O(θ³), and log inverts exp.
        let xi = Vector6::new(rho.x, rho.y, rho.z, w.x, w.y, w.z);
        let t = se3::exp(&xi);
        let expect = rho + w.cross(&rho) * 0.5 + w.cross(&w.cross(&rho)) / 6.0;
        prop_assert!((t.translation.vector - expect).norm() < 1e-12 * (1.0 + rho.norm()));
        let back = se3::log(&t);
        prop_assert!((back.fixed_rows::<3>(3) - w).norm() < 1e-12 * theta);
        prop_assert!((back.fixed_rows::<3>(0) - rho).norm() < 1e-12 * (1.0 + rho.norm()));
    }

    // ---------------------------------------------------------------- SE(3)

    #[test]
    fn se3_exp_log_round_trip(t in isometry()) {
        let back = se3::exp(&se3::log(&t));
        prop_assert!(iso_close(&back, &t, 1e-9), "{t} -> {back}");
    }

    #[test]
    fn se3_log_exp_round_trip(xi in twist()) {
        let back = se3::log(&se3::exp(&xi));
        prop_assert!((back - xi).norm() < 1e-9 * (1.0 + xi.norm()), "{xi} -> {back}");
    }

    #[test]
    fn se3_exp_rotation_is_so3_exp(xi in twist()) {
        let t = se3::exp(&xi);
        let phi = xi.fixed_rows::<3>(3).into_owned();
        let r = t.rotation.to_rotation_matrix().into_inner();
        prop_assert!((r - se3::so3_exp(&phi)).norm() < 1e-12);
        let rho = xi.fixed_rows::<3>(0).into_owned();
        prop_assert!((t.translation.vector - se3::so3_left_jacobian(&phi) * rho).norm() < 1e-12);
    }

    #[test]
    fn adjoint_conjugation(t in isometry(), xi in twist()) {
        let lhs = t * se3::exp(&xi) * t.inverse();
        let rhs = se3::exp(&(se3::adjoint(&t) * xi));
        prop_assert!(iso_close(&lhs, &rhs, 1e-9), "{lhs} vs {rhs}");
    }

    #[test]
    fn retract_local_round_trip(t in isometry(), xi in twist()) {
        let u = se3::retract(&t, &xi);
        let back = se3::local(&t, &u);
        prop_assert!((back - xi).norm() < 1e-8 * (1.0 + xi.norm()));
    }
}
