//! Plane-to-plane observation, GTSAM's `OrientedPlane3Factor`.
//!
//! The landmark is predicted in the sensor frame (`n_s = Rᵀ n_w`,
//! `d_s = d_w + n_w·t`, see `sensor_plane`) and compared with the measured
//! sensor-frame plane `(m, d_m)`:
//! `r = (B(n_s)ᵀ m, d_s − d_m)` (3-D), `B` the `Unit3` tangent basis. This
//! is the paper's plane-to-plane residual on the minimal S² × ℝ
//! parametrisation and exactly what GTSAM 4.3's `OrientedPlane3Factor`
//! evaluates (`OrientedPlane3::errorVector` → `Unit3::errorVector`, the
//! projection of `m` on the tangent plane, norm `sin θ`; *not*
//! `−localCoordinates`, norm `θ`, as some notes say): costs agree with GTSAM
//! to round-off for any 3×3 noise model, checked with
//! `paper/gtsam_solve.py`. Jacobians: the chain rule through
//! `unit3::error_vector_with_jacobian` (which differentiates GTSAM's basis)
//! and the sensor-plane Jacobians.

use nalgebra::{Matrix3, Matrix6, Vector6};

use super::sensor_plane::sensor_plane;
use super::Factor;
use crate::backend::unit3;
use crate::backend::variables::{Key, Values};
use crate::geometry::Plane;
use crate::Result;

/// Measured sensor-frame plane of landmark `plane` from pose `pose`, with a
/// 3×3 square-root information on `(normal tangent 2-D, offset)`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneObservation {
    keys: [Key; 2],
    ids: [u32; 2],
    /// The measured plane in the sensor frame.
    pub measured: Plane,
    /// Square-root information `S` (3×3).
    pub sqrt_info: Matrix3<f64>,
}

impl PlaneObservation {
    /// Landmark `plane` measured as `measured` from pose `pose`.
    pub fn new(pose: u32, plane: u32, measured: Plane, sqrt_info: Matrix3<f64>) -> Self {
        Self {
            keys: [Key::Pose(pose), Key::Plane(plane)],
            ids: [pose, plane],
            measured,
            sqrt_info,
        }
    }

    /// The `(pose, plane)` ids.
    pub fn ids(&self) -> (u32, u32) {
        (self.ids[0], self.ids[1])
    }
}

impl Factor for PlaneObservation {
    fn keys(&self) -> &[Key] {
        &self.keys
    }

    fn dim(&self) -> usize {
        3
    }

    fn evaluate(
        &self,
        values: &Values,
        jacobians: Option<&mut [Matrix6<f64>; 2]>,
    ) -> Result<Vector6<f64>> {
        let pose = values.pose(self.ids[0])?;
        let plane = values.plane(self.ids[1])?;
        let sp = sensor_plane(pose, plane);
        let (e, de) = unit3::error_vector_with_jacobian(&sp.normal, &self.measured.normal);
        let r = nalgebra::Vector3::new(e.x, e.y, sp.d - self.measured.d);
        if let Some(j) = jacobians {
            let mut jp = nalgebra::Matrix3x6::zeros();
            jp.fixed_view_mut::<2, 6>(0, 0)
                .copy_from(&(de * sp.dn_dpose));
            jp.fixed_view_mut::<1, 6>(2, 0).copy_from(&sp.dd_dpose);
            let mut jl = Matrix3::zeros();
            jl.fixed_view_mut::<2, 3>(0, 0)
                .copy_from(&(de * sp.dn_dplane));
            jl.fixed_view_mut::<1, 3>(2, 0).copy_from(&sp.dd_dplane);
            j[0].fill(0.0);
            j[1].fill(0.0);
            j[0].fixed_view_mut::<3, 6>(0, 0)
                .copy_from(&(self.sqrt_info * jp));
            j[1].fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(self.sqrt_info * jl));
        }
        let w = self.sqrt_info * r;
        Ok(Vector6::new(w.x, w.y, w.z, 0.0, 0.0, 0.0))
    }
}
