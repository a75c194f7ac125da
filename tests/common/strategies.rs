//! proptest strategies for geometry: vectors, points, poses, rotation
//! vectors and twists.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use proptest::prelude::*;

/// Vectors with every coordinate in `(-r, r)`.
pub fn vec3(r: f64) -> impl Strategy<Value = Vector3<f64>> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// Points with every coordinate in `(-r, r)`.
pub fn point3(r: f64) -> impl Strategy<Value = Point3<f64>> {
    vec3(r).prop_map(Point3::from)
}

/// Poses within 10 m of the origin, turned by up to about 170 degrees.
pub fn isometry() -> impl Strategy<Value = Isometry3<f64>> {
    (vec3(10.0), vec3(3.0)).prop_map(|(t, w)| {
        Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(w))
    })
}

/// A rotation vector with angle below `π - 1e-3` (uniform direction, angle
/// uniform with extra weight near 0 and π; no rejection).
pub fn rotvec() -> impl Strategy<Value = Vector3<f64>> {
    let angle = prop_oneof![
        4 => 0.0..PI - 1e-3,
        1 => PI - 1e-2..PI - 1e-3,
        1 => 0.0..1e-2,
    ];
    (-1.0..1.0f64, 0.0..2.0 * PI, angle).prop_map(|(z, az, a)| {
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * az.cos(), r * az.sin(), z) * a
    })
}

/// Twists `(ρ, φ)`: translation part within 10 m, rotation as [`rotvec`].
pub fn twist() -> impl Strategy<Value = Vector6<f64>> {
    (vec3(10.0), rotvec())
        .prop_map(|(rho, phi)| Vector6::new(rho.x, rho.y, rho.z, phi.x, phi.y, phi.z))
}

/// Whether two poses agree within `tol` (radians, and metres relative to
/// the translation's size).
pub fn iso_close(a: &Isometry3<f64>, b: &Isometry3<f64>, tol: f64) -> bool {
    a.rotation.angle_to(&b.rotation) < tol
        && (a.translation.vector - b.translation.vector).norm()
            < tol * (1.0 + a.translation.vector.norm())
}
