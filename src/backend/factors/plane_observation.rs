//! Plane-to-plane observation, GTSAM's `OrientedPlane3Factor`.
//!
//! The landmark is predicted in the sensor frame (`n_s = Rᵀ n_w`,
//! `d_s = d_w + n_w·t`, see `sensor_plane`) and compared with the measured
//! sensor-frame plane `(m, d_m)`:
//! `r = (−n_s.localCoordinates(m), d_s − d_m)` (3-D). This is the paper's
//! plane-to-plane residual on the minimal S² × ℝ parametrisation; with an
//! isotropic normal noise its cost equals GTSAM's exactly. Jacobians: the
//! chain rule through `unit3::local_coordinates_with_jacobian` (which
//! differentiates GTSAM's basis as well) and the sensor-plane Jacobians.

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
        let (local, dlocal) =
            unit3::local_coordinates_with_jacobian(&sp.normal, &self.measured.normal);
        let r = nalgebra::Vector3::new(-local.x, -local.y, sp.d - self.measured.d);
        if let Some(j) = jacobians {
            let mut jp = nalgebra::Matrix3x6::zeros();
            jp.fixed_view_mut::<2, 6>(0, 0)
                .copy_from(&(-(dlocal * sp.dn_dpose)));
            jp.fixed_view_mut::<1, 6>(2, 0).copy_from(&sp.dd_dpose);
            let mut jl = Matrix3::zeros();
            jl.fixed_view_mut::<2, 3>(0, 0)
                .copy_from(&(-(dlocal * sp.dn_dplane)));
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
