//! The world landmark seen from a pose, with Jacobians (GTSAM
//! `OrientedPlane3::transform`), shared by both plane factors.
//!
//! With `X = (R, t)` = `T_world_sensor` and the landmark `(n_w, d_w)`:
//! `n_s = Rᵀ n_w`, `d_s = d_w + n_w·t`. Under `X · exp(δ)`:
//! `∂n_s/∂(ρ, φ) = [0 | [n_s]×]`, `∂d_s/∂(ρ, φ) = [n_sᵀ | 0]`. Under the
//! landmark update `(Exp(B v), d + δd)`: `∂n_s/∂(v, δd) = [Rᵀ B | 0]`,
//! `∂d_s/∂(v, δd) = [tᵀ B | 1]`.

use nalgebra::{Isometry3, Matrix3, Matrix3x6, RowVector3, RowVector6, Vector3};

use super::super::unit3;
use super::super::variables::PlaneVar;
use crate::geometry::se3::hat;

/// The predicted sensor-frame plane and its Jacobians.
pub(crate) struct SensorPlane {
    /// `n_s`.
    pub normal: Vector3<f64>,
    /// `d_s`.
    pub d: f64,
    /// `∂n_s/∂δ_pose`.
    pub dn_dpose: Matrix3x6<f64>,
    /// `∂d_s/∂δ_pose`.
    pub dd_dpose: RowVector6<f64>,
    /// `∂n_s/∂δ_plane`.
    pub dn_dplane: Matrix3<f64>,
    /// `∂d_s/∂δ_plane`.
    pub dd_dplane: RowVector3<f64>,
}

/// Landmark `plane` (world) expressed in the frame of `pose`.
pub(crate) fn sensor_plane(pose: &Isometry3<f64>, plane: &PlaneVar) -> SensorPlane {
    let rt = pose.rotation.inverse();
    let t = pose.translation.vector;
    let normal = rt * plane.normal;
    let d = plane.d + plane.normal.dot(&t);
    let mut dn_dpose = Matrix3x6::zeros();
    dn_dpose
        .fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&hat(&normal));
    let mut dd_dpose = RowVector6::zeros();
    dd_dpose
        .fixed_view_mut::<1, 3>(0, 0)
        .copy_from(&normal.transpose());
    let b = unit3::basis(&plane.normal);
    let rb = rt.to_rotation_matrix().into_inner() * b;
    let mut dn_dplane = Matrix3::zeros();
    dn_dplane.fixed_view_mut::<3, 2>(0, 0).copy_from(&rb);
    let tb = t.transpose() * b;
    let dd_dplane = RowVector3::new(tb[0], tb[1], 1.0);
    SensorPlane {
        normal,
        d,
        dn_dpose,
        dd_dpose,
        dn_dplane,
        dd_dplane,
    }
}
