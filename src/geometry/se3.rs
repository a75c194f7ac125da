//! SE(3) and SO(3) exponential and logarithm maps and their Jacobians.
//!
//! Tangent vectors of SE(3) are ordered `ξ = (ρ, φ)`: translation part first,
//! rotation part second, matching the paper's `(x, y, z, r_x, r_y, r_z)`.
//! `exp(ξ)` is the true group exponential (`t = V(φ) ρ`), not
//! `Isometry3::new`, which takes the translation as-is.

use nalgebra::{Isometry3, Matrix3, Vector3, Vector6};

/// Skew-symmetric matrix `[w]×` with `[w]× v = w × v`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    todo!("{w}")
}

/// SO(3) exponential as a rotation matrix (Rodrigues), stable near zero.
pub fn so3_exp(phi: &Vector3<f64>) -> Matrix3<f64> {
    todo!("{phi}")
}

/// SO(3) logarithm: the rotation vector with angle in `[0, π]`.
pub fn so3_log(r: &Matrix3<f64>) -> Vector3<f64> {
    todo!("{r}")
}

/// Left Jacobian of SO(3), `J_l(φ)`; also the `V(φ)` of the SE(3) exponential.
pub fn so3_left_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    todo!("{phi}")
}

/// Inverse of the left Jacobian of SO(3).
pub fn so3_left_jacobian_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    todo!("{phi}")
}

/// Right Jacobian of SO(3), `J_r(φ) = J_l(-φ)`.
pub fn so3_right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    so3_left_jacobian(&-phi)
}

/// SE(3) exponential of `ξ = (ρ, φ)`.
pub fn exp(xi: &Vector6<f64>) -> Isometry3<f64> {
    todo!("{xi}")
}

/// SE(3) logarithm, inverse of [`exp`] for rotation angles below π.
pub fn log(t: &Isometry3<f64>) -> Vector6<f64> {
    todo!("{t}")
}

/// Right-perturbation update `T · exp(δ)` used by Gauss-Newton on poses.
pub fn retract(t: &Isometry3<f64>, delta: &Vector6<f64>) -> Isometry3<f64> {
    t * exp(delta)
}

/// Inverse of [`retract`]: `log(T_a⁻¹ T_b)`.
pub fn local(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vector6<f64> {
    log(&(a.inverse() * b))
}
