//! Point-to-plane factor on a scatter summary (BALM2 / π-LSAM style).
//!
//! One observation's inliers `p_i` (sensor frame) are summarised by their
//! count `N`, centroid `c` and centred scatter `C = Σ (p_i − c)(p_i − c)ᵀ`.
//! With the predicted sensor-frame plane `(n_s, d_s)`:
//! `Σ_i (n_s·p_i + d_s)² = N (n_s·c + d_s)² + n_sᵀ C n_s`,
//! which is `‖r‖²·σ²` for the 4-D residual
//! `r = [√N (n_s·c + d_s); Lᵀ n_s] / σ`, `C = L Lᵀ` (`L = V Λ^½` from the
//! eigen-decomposition, so a rank-deficient scatter is fine). `σ` is the
//! point noise in metres, so metres and radians are weighed by the data.
//! Jacobians: `∂r/∂n_s = [√N cᵀ; Lᵀ] / σ`, `∂r/∂d_s = [√N; 0] / σ`,
//! chained with the sensor-plane Jacobians.

use nalgebra::{Matrix3, Matrix4x3, Matrix6, SymmetricEigen, Vector3, Vector4, Vector6};

use super::sensor_plane::sensor_plane;
use super::Factor;
use crate::backend::variables::{Key, Values};
use crate::{Error, Result};

/// Inliers of one plane observation summarised as `(N, c, C)`, with the
/// point noise `σ` (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct PointToPlane {
    keys: [Key; 2],
    ids: [u32; 2],
    /// Number of inlier points `N`.
    pub count: f64,
    /// Centroid `c` (sensor frame).
    pub centroid: Vector3<f64>,
    /// Centred scatter `C` (sensor frame, symmetric PSD).
    pub scatter: Matrix3<f64>,
    /// Point noise `σ` in metres.
    pub sigma: f64,
    /// `Lᵀ` with `C = L Lᵀ`, cached at construction.
    sqrt_scatter_t: Matrix3<f64>,
}

impl PointToPlane {
    /// A factor from a scatter summary; an error if `N < 1`, `σ ≤ 0`, any
    /// number is not finite or the scatter is not symmetric PSD.
    pub fn new(
        pose: u32,
        plane: u32,
        count: f64,
        centroid: Vector3<f64>,
        scatter: Matrix3<f64>,
        sigma: f64,
    ) -> Result<Self> {
        let finite = centroid.iter().chain(scatter.iter()).all(|v| v.is_finite());
        if !(count >= 1.0) || !count.is_finite() || !(sigma > 0.0) || !sigma.is_finite() || !finite
        {
            return Err(Error::Input(format!(
                "point_to_plane x{pose}-p{plane}: need count ≥ 1, sigma > 0 and finite numbers"
            )));
        }
        let asym = (scatter - scatter.transpose()).abs().max();
        let scale = scatter.abs().max().max(1e-300);
        if asym > 1e-9 * scale {
            return Err(Error::Input(format!(
                "point_to_plane x{pose}-p{plane}: scatter is not symmetric"
            )));
        }
        let eig = SymmetricEigen::new(0.5 * (scatter + scatter.transpose()));
        if eig.eigenvalues.min() < -1e-9 * scale {
            return Err(Error::Input(format!(
                "point_to_plane x{pose}-p{plane}: scatter is not positive semi-definite"
            )));
        }
        let sqrt_l = eig.eigenvalues.map(|l| l.max(0.0).sqrt());
        // L = V Λ^½  ⇒  Lᵀ = Λ^½ Vᵀ.
        let sqrt_scatter_t = Matrix3::from_diagonal(&sqrt_l) * eig.eigenvectors.transpose();
        Ok(Self {
            keys: [Key::Pose(pose), Key::Plane(plane)],
            ids: [pose, plane],
            count,
            centroid,
            scatter,
            sigma,
            sqrt_scatter_t,
        })
    }

    /// Summarise sensor-frame inlier points (one pass for the centroid, one
    /// for the scatter; no allocation).
    pub fn from_points(pose: u32, plane: u32, points: &[Vector3<f64>], sigma: f64) -> Result<Self> {
        let n = points.len() as f64;
        let c = points.iter().fold(Vector3::zeros(), |a, p| a + p) / n.max(1.0);
        let s = points.iter().fold(Matrix3::zeros(), |a, p| {
            let q = p - c;
            a + q * q.transpose()
        });
        Self::new(pose, plane, n, c, s, sigma)
    }

    /// The `(pose, plane)` ids.
    pub fn ids(&self) -> (u32, u32) {
        (self.ids[0], self.ids[1])
    }

    /// The least-squares plane of the summarised points (sensor frame,
    /// oriented so the sensor origin is on its positive side): the normal is
    /// the scatter's eigenvector of smallest eigenvalue.
    pub fn fitted_plane(&self) -> Option<crate::geometry::Plane> {
        let eig = SymmetricEigen::new(self.scatter);
        let k = eig.eigenvalues.imin();
        let n = eig.eigenvectors.column(k).into_owned();
        crate::geometry::Plane::from_point_normal(&self.centroid.into(), &n)
            .map(|p| p.facing(&nalgebra::Point3::origin()))
    }
}

impl Factor for PointToPlane {
    fn keys(&self) -> &[Key] {
        &self.keys
    }

    fn dim(&self) -> usize {
        4
    }

    fn evaluate(
        &self,
        values: &Values,
        jacobians: Option<&mut [Matrix6<f64>; 2]>,
    ) -> Result<Vector6<f64>> {
        let pose = values.pose(self.ids[0])?;
        let plane = values.plane(self.ids[1])?;
        let sp = sensor_plane(pose, plane);
        let inv_sigma = 1.0 / self.sigma;
        let sqrt_n = self.count.sqrt();
        let lt_n = self.sqrt_scatter_t * sp.normal;
        let r = Vector4::new(
            sqrt_n * (sp.normal.dot(&self.centroid) + sp.d),
            lt_n.x,
            lt_n.y,
            lt_n.z,
        ) * inv_sigma;
        if let Some(j) = jacobians {
            // ∂r/∂n_s (4×3) and ∂r/∂d_s (4×1).
            let mut dr_dn = Matrix4x3::zeros();
            dr_dn
                .fixed_view_mut::<1, 3>(0, 0)
                .copy_from(&(self.centroid.transpose() * sqrt_n));
            dr_dn
                .fixed_view_mut::<3, 3>(1, 0)
                .copy_from(&self.sqrt_scatter_t);
            dr_dn *= inv_sigma;
            let dr_dd = Vector4::new(sqrt_n * inv_sigma, 0.0, 0.0, 0.0);
            let jp = dr_dn * sp.dn_dpose + dr_dd * sp.dd_dpose;
            let jl = dr_dn * sp.dn_dplane + dr_dd * sp.dd_dplane;
            j[0].fill(0.0);
            j[1].fill(0.0);
            j[0].fixed_view_mut::<4, 6>(0, 0).copy_from(&jp);
            j[1].fixed_view_mut::<4, 3>(0, 0).copy_from(&jl);
        }
        Ok(Vector6::new(r.x, r.y, r.z, r.w, 0.0, 0.0))
    }
}
