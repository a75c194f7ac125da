//! Our plane factors (and a between factor with a fixed end) as factrs
//! residuals, with Jacobians by factrs' forward-mode autodiff (num-dual):
//! an independent check of the analytic Jacobians in `backend::factors`.
//!
//! A plane measurement is a [`PlaneModel`] (the residual of one pose and one
//! landmark); fixed variables of our graph are baked into the residual as
//! constants, so each model comes in three arities: [`PoseAndPlane`] (both
//! free), [`PoseOnly`] (landmark fixed) and [`PlaneOnly`] (pose fixed).
//! Residuals are unwhitened here; the factor's noise model whitens them.

use std::fmt::Debug;

use factrs::linalg::{Const, DimName, ForwardProp, Numeric, Vector3, VectorX};
use factrs::residuals::{Residual1, Residual2};
use factrs::variables::{MatrixLieGroup, Variable, SE3};

use super::plane::{basis, c, FactrsPlane};

/// The landmark seen from the pose: `n_s = Rᵀ n_w`, `d_s = d_w + n_w·t`.
pub(crate) fn sensor_plane<T: Numeric>(pose: &SE3<T>, plane: &FactrsPlane<T>) -> (Vector3<T>, T) {
    let n_s = pose.rot().inverse().apply(plane.normal.as_view());
    let t = pose.xyz();
    let d_s = plane.d + plane.normal.x * t[0] + plane.normal.y * t[1] + plane.normal.z * t[2];
    (n_s, d_s)
}

/// A residual of one pose and one plane landmark.
pub trait PlaneModel: Clone + Debug + 'static {
    /// Residual dimension as a type.
    type DimOut: DimName;
    /// The (unwhitened) residual.
    fn eval<T: Numeric>(&self, pose: &SE3<T>, plane: &FactrsPlane<T>) -> VectorX<T>;
}

/// GTSAM 4.3 `OrientedPlane3Factor` as our `PlaneObservation`:
/// `r = (B(n_s)ᵀ m, d_s − d_m)` (`Unit3::errorVector`, the projection of the
/// measured normal `m` on the predicted normal's tangent basis) for the
/// measured sensor-frame plane `(m, d_m)`, whitened by the factor's 3×3
/// square-root information.
#[derive(Clone, Debug)]
pub struct PlaneToPlaneModel {
    /// Measured sensor-frame unit normal.
    pub normal: [f64; 3],
    /// Measured sensor-frame offset.
    pub d: f64,
}

impl PlaneModel for PlaneToPlaneModel {
    type DimOut = Const<3>;
    fn eval<T: Numeric>(&self, pose: &SE3<T>, plane: &FactrsPlane<T>) -> VectorX<T> {
        let (n_s, d_s) = sensor_plane(pose, plane);
        let m = Vector3::new(
            c::<T>(self.normal[0]),
            c::<T>(self.normal[1]),
            c::<T>(self.normal[2]),
        );
        let (b1, b2) = basis(&n_s);
        VectorX::from_vec(vec![b1.dot(&m), b2.dot(&m), d_s - c::<T>(self.d)])
    }
}

/// Point-to-plane on a scatter summary:
/// `r = [√N (n_s·c + d_s); Lᵀ n_s]` with `C = L Lᵀ` (whitened by `1/σ`).
#[derive(Clone, Debug)]
pub struct PointToPlaneModel {
    /// `√N`.
    pub sqrt_count: f64,
    /// Centroid `c` (sensor frame).
    pub centroid: [f64; 3],
    /// `Lᵀ`, row-major.
    pub sqrt_scatter_t: [[f64; 3]; 3],
}

impl PlaneModel for PointToPlaneModel {
    type DimOut = Const<4>;
    fn eval<T: Numeric>(&self, pose: &SE3<T>, plane: &FactrsPlane<T>) -> VectorX<T> {
        let (n, d_s) = sensor_plane(pose, plane);
        let dot =
            |row: &[f64; 3]| n.x * c::<T>(row[0]) + n.y * c::<T>(row[1]) + n.z * c::<T>(row[2]);
        let l = &self.sqrt_scatter_t;
        VectorX::from_vec(vec![
            (dot(&self.centroid) + d_s) * c::<T>(self.sqrt_count),
            dot(&l[0]),
            dot(&l[1]),
            dot(&l[2]),
        ])
    }
}

/// A plane model with both variables free.
#[derive(Clone, Debug)]
pub struct PoseAndPlane<M> {
    /// The measurement.
    pub model: M,
}

#[factrs::mark]
impl<M: PlaneModel> Residual2 for PoseAndPlane<M> {
    type Differ = ForwardProp<Const<9>>;
    type V1 = SE3;
    type V2 = FactrsPlane;
    type DimIn = Const<9>;
    type DimOut = M::DimOut;

    fn residual2<T: Numeric>(&self, pose: SE3<T>, plane: FactrsPlane<T>) -> VectorX<T> {
        self.model.eval(&pose, &plane)
    }
}

/// A plane model whose landmark is fixed (a constant of the residual).
#[derive(Clone, Debug)]
pub struct PoseOnly<M> {
    /// The measurement.
    pub model: M,
    /// The fixed landmark.
    pub plane: FactrsPlane,
}

#[factrs::mark]
impl<M: PlaneModel> Residual1 for PoseOnly<M> {
    type Differ = ForwardProp<Const<6>>;
    type V1 = SE3;
    type DimIn = Const<6>;
    type DimOut = M::DimOut;

    fn residual1<T: Numeric>(&self, pose: SE3<T>) -> VectorX<T> {
        self.model.eval(&pose, &self.plane.cast::<T>())
    }
}

/// A plane model whose pose is fixed (a constant of the residual).
#[derive(Clone, Debug)]
pub struct PlaneOnly<M> {
    /// The measurement.
    pub model: M,
    /// The fixed pose.
    pub pose: SE3,
}

#[factrs::mark]
impl<M: PlaneModel> Residual1 for PlaneOnly<M> {
    type Differ = ForwardProp<Const<3>>;
    type V1 = FactrsPlane;
    type DimIn = Const<3>;
    type DimOut = M::DimOut;

    fn residual1<T: Numeric>(&self, plane: FactrsPlane<T>) -> VectorX<T> {
        self.model.eval(&self.pose.cast::<T>(), &plane)
    }
}

/// factrs' `BetweenResidual` with its second pose fixed:
/// `r = log(X_j⁻¹ · X_i · Z)` in factrs' `(ω, v)` order.
#[derive(Clone, Debug)]
pub struct BetweenToFixed {
    /// Measured `Z = X_i⁻¹ X_j`.
    pub measured: SE3,
    /// The fixed `X_j`.
    pub fixed_j: SE3,
}

#[factrs::mark]
impl Residual1 for BetweenToFixed {
    type Differ = ForwardProp<Const<6>>;
    type V1 = SE3;
    type DimIn = Const<6>;
    type DimOut = Const<6>;

    fn residual1<T: Numeric>(&self, xi: SE3<T>) -> VectorX<T> {
        xi.compose(&self.measured.cast::<T>())
            .ominus(&self.fixed_j.cast::<T>())
    }
}
