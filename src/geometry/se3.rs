//! SE(3) and SO(3) exponential and logarithm maps and their Jacobians.
//!
//! Tangent vectors of SE(3) are ordered `ξ = (ρ, φ)`: translation part first,
//! rotation part second, matching the paper's `(x, y, z, r_x, r_y, r_z)`.
//! `exp(ξ)` is the true group exponential (`t = V(φ) ρ`), not
//! `Isometry3::new`, which takes the translation as-is.
//!
//! Every coefficient that suffers from cancellation near `θ = 0` switches to
//! its Taylor series below `SMALL_ANGLE`, so tiny rotations (`|φ| ~ 1e-9`)
//! stay accurate to machine precision.

use nalgebra::{
    Isometry3, Matrix3, Matrix6, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3,
    Vector6,
};

/// Angle (radians) below which the Jacobian coefficients use Taylor series
/// instead of their closed forms (which cancel catastrophically near zero).
const SMALL_ANGLE: f64 = 1e-2;

/// Skew-symmetric matrix `[w]×` with `[w]× v = w × v`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// Inverse of [`hat`]: the vector of the skew-symmetric part of `m`
/// (`vee([w]×) = w`). Used by the logarithm and by tests of the Jacobians.
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// `sin θ / θ`, exact at 0.
fn sinc(theta: f64) -> f64 {
    if theta < SMALL_ANGLE {
        let t2 = theta * theta;
        1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0))
    } else {
        theta.sin() / theta
    }
}

/// `(1 - cos θ) / θ²`, computed as `2 sin²(θ/2) / θ²` (no cancellation).
fn one_minus_cos_over_t2(theta: f64) -> f64 {
    if theta < SMALL_ANGLE {
        let t2 = theta * theta;
        0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0))
    } else {
        let s = (0.5 * theta).sin();
        2.0 * s * s / (theta * theta)
    }
}

/// `(θ - sin θ) / θ³`.
fn t_minus_sin_over_t3(theta: f64) -> f64 {
    if theta < SMALL_ANGLE {
        let t2 = theta * theta;
        1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))
    } else {
        (theta - theta.sin()) / (theta * theta * theta)
    }
}

/// `(1 - (θ/2) cot(θ/2)) / θ²`, the `[φ]×²` coefficient of `J_l⁻¹`.
fn inv_jacobian_coeff(theta: f64) -> f64 {
    if theta < SMALL_ANGLE {
        let t2 = theta * theta;
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    } else {
        let half = 0.5 * theta;
        (1.0 - half * half.cos() / half.sin()) / (theta * theta)
    }
}

/// SO(3) exponential as a rotation matrix (Rodrigues), stable near zero.
pub fn so3_exp(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = hat(phi);
    Matrix3::identity() + k * sinc(theta) + k * k * one_minus_cos_over_t2(theta)
}

/// SO(3) exponential as a unit quaternion, stable near zero. Preferred over
/// [`so3_exp`] when building an `Isometry3`, which stores a quaternion.
pub fn so3_exp_quat(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let theta = phi.norm();
    let half = 0.5 * theta;
    // sin(θ/2)/θ = ½ sinc(θ/2)
    let s = 0.5 * sinc(half);
    UnitQuaternion::new_normalize(Quaternion::new(half.cos(), phi.x * s, phi.y * s, phi.z * s))
}

/// SO(3) logarithm of a unit quaternion: the rotation vector with angle in
/// `[0, π]`. Robust near 0 (no division by a vanishing sine) and near π (the
/// double cover is resolved by taking `w ≥ 0`).
pub fn so3_log_quat(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (mut w, mut v) = (q.w, q.imag());
    if w < 0.0 {
        w = -w;
        v = -v;
    }
    let n = v.norm();
    // θ = 2 atan2(n, w); φ = v θ / n.
    let scale = if n < 1e-8 {
        // atan2(n, w)/n = (1/w)(1 - n²/(3w²) + …); w ≈ 1 here.
        2.0 / w * (1.0 - n * n / (3.0 * w * w))
    } else {
        2.0 * n.atan2(w) / n
    };
    v * scale
}

/// SO(3) logarithm: the rotation vector with angle in `[0, π]`.
///
/// `r` is assumed to be (close to) a rotation matrix; it is converted to a
/// quaternion (Shepperd's method, well conditioned everywhere) first.
pub fn so3_log(r: &Matrix3<f64>) -> Vector3<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r));
    so3_log_quat(&q)
}

/// Left Jacobian of SO(3), `J_l(φ)`; also the `V(φ)` of the SE(3) exponential.
pub fn so3_left_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = hat(phi);
    Matrix3::identity() + k * one_minus_cos_over_t2(theta) + k * k * t_minus_sin_over_t3(theta)
}

/// Inverse of the left Jacobian of SO(3).
pub fn so3_left_jacobian_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = hat(phi);
    Matrix3::identity() - k * 0.5 + k * k * inv_jacobian_coeff(theta)
}

/// Right Jacobian of SO(3), `J_r(φ) = J_l(-φ)`.
pub fn so3_right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    so3_left_jacobian(&-phi)
}

/// SE(3) exponential of `ξ = (ρ, φ)`.
pub fn exp(xi: &Vector6<f64>) -> Isometry3<f64> {
    let rho = xi.fixed_rows::<3>(0).into_owned();
    let phi = xi.fixed_rows::<3>(3).into_owned();
    let t = so3_left_jacobian(&phi) * rho;
    Isometry3::from_parts(Translation3::from(t), so3_exp_quat(&phi))
}

/// SE(3) logarithm, inverse of [`exp`] for rotation angles below π.
pub fn log(t: &Isometry3<f64>) -> Vector6<f64> {
    let phi = so3_log_quat(&t.rotation);
    let rho = so3_left_jacobian_inv(&phi) * t.translation.vector;
    Vector6::new(rho.x, rho.y, rho.z, phi.x, phi.y, phi.z)
}

/// Adjoint of `T = (R, t)` for the `ξ = (ρ, φ)` ordering:
/// `[[R, [t]× R], [0, R]]`, so that `T · exp(ξ) · T⁻¹ = exp(Ad(T) ξ)`.
///
/// The back-end needs it to move perturbations and covariances between the
/// left and right of a pose (e.g. relative-pose factors).
pub fn adjoint(t: &Isometry3<f64>) -> Matrix6<f64> {
    let r = t.rotation.to_rotation_matrix().into_inner();
    let tr = hat(&t.translation.vector) * r;
    let mut ad = Matrix6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&tr);
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    ad
}

/// `Q(ρ, φ)`, the upper-right block of the SE(3) left Jacobian (Barfoot,
/// *State Estimation for Robotics*, eq. 7.86), stable near `θ = 0`.
fn se3_q(rho: &Vector3<f64>, phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let t2 = theta * theta;
    let (c2, c3) = if theta < SMALL_ANGLE {
        (
            1.0 / 24.0 - t2 / 720.0 + t2 * t2 / 40320.0,
            1.0 / 120.0 - t2 / 2520.0 + t2 * t2 / 120960.0,
        )
    } else {
        let (s, c) = theta.sin_cos();
        (
            (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2),
            (2.0 * theta - 3.0 * s + theta * c) / (2.0 * t2 * t2 * theta),
        )
    };
    let c1 = t_minus_sin_over_t3(theta);
    let p = hat(phi);
    let r = hat(rho);
    let pr = p * r;
    let rp = r * p;
    let prp = pr * p;
    r * 0.5 + (pr + rp + prp) * c1 + (p * pr + rp * p - prp * 3.0) * c2 + (prp * p + p * prp) * c3
}

/// Left Jacobian of SE(3) for `ξ = (ρ, φ)`: `[[J_l(φ), Q(ρ, φ)], [0, J_l(φ)]]`,
/// so that `exp(ξ + δ) ≈ exp(J_l(ξ) δ) · exp(ξ)`.
pub fn se3_left_jacobian(xi: &Vector6<f64>) -> Matrix6<f64> {
    let rho = xi.fixed_rows::<3>(0).into_owned();
    let phi = xi.fixed_rows::<3>(3).into_owned();
    let j = so3_left_jacobian(&phi);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&j);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&j);
    out.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&se3_q(&rho, &phi));
    out
}

/// Inverse of the right Jacobian of SE(3), `J_r⁻¹(ξ) = J_l⁻¹(-ξ)`, in closed
/// form: `[[A⁻¹, -A⁻¹ Q A⁻¹], [0, A⁻¹]]` with `A = J_l(-φ)`, `Q = Q(-ρ, -φ)`.
///
/// The back-end needs it for the Jacobian of `log(Z⁻¹ X)` under the right
/// perturbation `X · exp(δ)`: `∂ log / ∂δ = J_r⁻¹(log(Z⁻¹ X))`.
pub fn se3_right_jacobian_inv(xi: &Vector6<f64>) -> Matrix6<f64> {
    let rho = -xi.fixed_rows::<3>(0).into_owned();
    let phi = -xi.fixed_rows::<3>(3).into_owned();
    let a_inv = so3_left_jacobian_inv(&phi);
    let q = se3_q(&rho, &phi);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&a_inv);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&a_inv);
    out.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-(a_inv * q * a_inv)));
    out
}

/// Right-perturbation update `T · exp(δ)` used by Gauss-Newton on poses.
pub fn retract(t: &Isometry3<f64>, delta: &Vector6<f64>) -> Isometry3<f64> {
    t * exp(delta)
}

/// Inverse of [`retract`]: `log(T_a⁻¹ T_b)`.
pub fn local(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vector6<f64> {
    log(&(a.inverse() * b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hat_is_cross_product() {
        let w = Vector3::new(0.3, -1.2, 2.0);
        let v = Vector3::new(-0.7, 0.1, 0.4);
        assert!((hat(&w) * v - w.cross(&v)).norm() < 1e-15);
        assert_eq!(vee(&hat(&w)), w);
    }

    #[test]
    fn exp_matches_nalgebra() {
        let phi = Vector3::new(0.4, -0.2, 1.1);
        let r = so3_exp(&phi);
        let q = UnitQuaternion::from_scaled_axis(phi);
        assert!((r - q.to_rotation_matrix().into_inner()).norm() < 1e-14);
        assert!((so3_exp_quat(&phi).angle_to(&q)) < 1e-14);
    }

    #[test]
    fn log_at_pi_and_zero() {
        let axis = Vector3::new(1.0, 2.0, -2.0).normalize();
        let phi = axis * std::f64::consts::PI;
        let back = so3_log(&so3_exp(&phi));
        assert!((back.norm() - std::f64::consts::PI).abs() < 1e-9);
        assert!(back.normalize().dot(&axis).abs() > 1.0 - 1e-12);
        assert_eq!(so3_log(&Matrix3::identity()), Vector3::zeros());
        assert_eq!(log(&Isometry3::identity()), Vector6::zeros());
    }

    #[test]
    fn se3_exp_translation_uses_left_jacobian() {
        // Pure rotation about z with ρ along x: a screw, not a straight line.
        let xi = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let t = exp(&xi);
        let expect = Vector3::new(2.0 / std::f64::consts::PI, 2.0 / std::f64::consts::PI, 0.0);
        assert!((t.translation.vector - expect).norm() < 1e-14);
    }
}
