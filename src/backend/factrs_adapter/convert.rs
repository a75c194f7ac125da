//! Across the boundary: our factor graph and values as a factrs problem
//! (fixed variables baked into the residuals as constants), and factrs'
//! values back as ours. factrs has its own nalgebra, so everything crosses
//! as plain `f64` arrays.

use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};

use factrs::containers::{Factor, FactorBuilder, Graph, Values as FValues};
use factrs::linalg::{Matrix3 as FMatrix3, Matrix6 as FMatrix6, Vector3 as FVector3};
use factrs::noise::GaussianNoise;
use factrs::residuals::{BetweenResidual, PriorResidual};
use factrs::robust::{Cauchy, Huber};
use factrs::variables::{SE3, SO3};
use nalgebra::{
    Isometry3, Matrix3, Matrix6, Quaternion, SymmetricEigen, Translation3, UnitQuaternion,
};

use super::plane::FactrsPlane;
use super::residuals::{
    BetweenToFixed, PlaneModel, PlaneOnly, PlaneToPlaneModel, PointToPlaneModel, PoseAndPlane,
    PoseOnly,
};
use crate::backend::factors::{
    AnyFactor, Factor as _, GraphFactor, PlaneObservation, PointToPlane,
};
use crate::backend::graph::FactorGraph;
use crate::backend::robust::RobustKernel;
use crate::backend::variables::{Key, PlaneVar, Values};
use crate::{Error, Result};

/// factrs symbols: `X` poses, `L` plane landmarks (private: the macro makes
/// undocumented public structs).
mod symbols {
    use super::{FactrsPlane, SE3};
    use factrs::assign_symbols;
    assign_symbols!(X: SE3; L: FactrsPlane);
}
use symbols::{L, X};

/// A converted problem: the factrs graph, the free variables' values and
/// which of our factors each factrs factor came from.
pub struct FactrsProblem {
    /// The factrs factor graph.
    pub graph: Graph,
    /// Initial values of the free variables that some factor touches.
    pub values: FValues,
    /// Those variables (the ones copied back after the solve).
    pub free: BTreeSet<Key>,
    /// For each factrs factor, the index of our factor it converts.
    pub source: Vec<usize>,
}

/// Convert `graph` at `values` with the variables in `fixed` held constant.
/// Factors whose variables are all fixed are left out (their cost is a
/// constant); free variables no factor touches are not factrs variables.
pub fn convert(
    graph: &FactorGraph,
    values: &Values,
    fixed: &BTreeSet<Key>,
) -> Result<FactrsProblem> {
    let mut fgraph = Graph::with_capacity(graph.factors.len());
    let mut source = Vec::with_capacity(graph.factors.len());
    let mut free = BTreeSet::new();
    for (index, gf) in graph.factors.iter().enumerate() {
        let added = add_factor(&mut fgraph, gf, values, fixed)?;
        if added {
            source.push(index);
            free.extend(gf.factor.keys().iter().filter(|k| !fixed.contains(k)));
        }
    }
    let mut fvalues = FValues::new();
    for &key in &free {
        match key {
            Key::Pose(id) => {
                fvalues.insert(X(id), to_se3(values.pose(id)?));
            }
            Key::Plane(id) => {
                fvalues.insert(L(id), to_plane(values.plane(id)?));
            }
        }
    }
    Ok(FactrsProblem {
        graph: fgraph,
        values: fvalues,
        free,
        source,
    })
}

/// Each converted factor's factrs cost (`loss(‖S r‖²)`, our `½ ρ`) at
/// `values`, indexed like `graph.factors`; `None` for factors left out
/// because all their variables are fixed. For tests and diagnostics.
pub fn converted_costs(
    graph: &FactorGraph,
    values: &Values,
    fixed: &BTreeSet<Key>,
) -> Result<Vec<Option<f64>>> {
    let problem = convert(graph, values, fixed)?;
    let mut out = vec![None; graph.factors.len()];
    for (k, &index) in problem.source.iter().enumerate() {
        let f = problem.graph.at(k);
        let cost = catch_unwind(AssertUnwindSafe(|| f.error(&problem.values)))
            .map_err(|_| Error::Input(format!("factrs could not evaluate factor {index}")))?;
        out[index] = Some(cost);
    }
    Ok(out)
}

/// One converted factor linearised by factrs (autodiff), in factrs'
/// conventions: pose columns in `(ω, v)` order, pose-factor residuals
/// negated with respect to ours (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FactrsLinearization {
    /// The free variables, in column-block order.
    pub keys: Vec<Key>,
    /// Whitened, robust-weighted residual `√ρ'(s) S r`.
    pub residual: Vec<f64>,
    /// Whitened, robust-weighted Jacobian, one `Vec` per row.
    pub jacobian: Vec<Vec<f64>>,
}

/// Each converted factor's factrs linearisation at `values`, indexed like
/// `graph.factors` (`None` for factors left out). For tests: it checks our
/// analytic Jacobians against factrs' autodiff of independent code.
pub fn converted_linearizations(
    graph: &FactorGraph,
    values: &Values,
    fixed: &BTreeSet<Key>,
) -> Result<Vec<Option<FactrsLinearization>>> {
    let problem = convert(graph, values, fixed)?;
    let mut out = vec![None; graph.factors.len()];
    for (k, &index) in problem.source.iter().enumerate() {
        let f = problem.graph.at(k);
        let lin = catch_unwind(AssertUnwindSafe(|| f.linearize(&problem.values)))
            .map_err(|_| Error::Input(format!("factrs could not linearise factor {index}")))?;
        let a = lin.a.mat();
        out[index] = Some(FactrsLinearization {
            keys: graph.factors[index]
                .factor
                .keys()
                .iter()
                .copied()
                .filter(|key| !fixed.contains(key))
                .collect(),
            residual: lin.b.iter().map(|b| -b).collect(),
            jacobian: (0..a.nrows())
                .map(|r| (0..a.ncols()).map(|c| a[(r, c)]).collect())
                .collect(),
        });
    }
    Ok(out)
}

/// Add the factrs version of one factor; `false` if all its keys are fixed.
fn add_factor(
    fgraph: &mut Graph,
    gf: &GraphFactor,
    values: &Values,
    fixed: &BTreeSet<Key>,
) -> Result<bool> {
    let kernel = gf.robust;
    let factor = match &gf.factor {
        AnyFactor::PosePrior(f) => {
            let id = f.pose();
            if fixed.contains(&Key::Pose(id)) {
                return Ok(false);
            }
            let res = PriorResidual::new(to_se3(&f.prior));
            finish(
                FactorBuilder::<6>::new1(res, X(id)),
                pose_noise(&f.sqrt_info),
                kernel,
            )
        }
        AnyFactor::Between(f) => {
            let (i, j) = f.poses();
            let noise = pose_noise(&f.sqrt_info);
            let z = to_se3(&f.measured);
            match (fixed.contains(&Key::Pose(i)), fixed.contains(&Key::Pose(j))) {
                (true, true) => return Ok(false),
                (false, false) => finish(
                    FactorBuilder::<6>::new2(BetweenResidual::new(z), X(i), X(j)),
                    noise,
                    kernel,
                ),
                // log(X_j⁻¹ · (X_i Z)) is factrs' prior on X_j at X_i Z.
                (true, false) => {
                    let xi_z = values.pose(i)? * f.measured;
                    let res = PriorResidual::new(to_se3(&xi_z));
                    finish(FactorBuilder::<6>::new1(res, X(j)), noise, kernel)
                }
                (false, true) => {
                    let res = BetweenToFixed {
                        measured: z,
                        fixed_j: to_se3(values.pose(j)?),
                    };
                    finish(FactorBuilder::<6>::new1(res, X(i)), noise, kernel)
                }
            }
        }
        AnyFactor::PlaneObservation(f) => {
            let (pose, plane) = f.ids();
            let noise = GaussianNoise::<3>::from_matrix_sqrt_inf(mat3(&f.sqrt_info));
            match plane_factor::<_, 3>(
                plane_to_plane(f),
                pose,
                plane,
                values,
                fixed,
                noise,
                kernel,
            )? {
                Some(factor) => factor,
                None => return Ok(false),
            }
        }
        AnyFactor::PointToPlane(f) => {
            let (pose, plane) = f.ids();
            let noise = GaussianNoise::<4>::from_scalar_sigma(f.sigma);
            match plane_factor::<_, 4>(
                point_to_plane(f)?,
                pose,
                plane,
                values,
                fixed,
                noise,
                kernel,
            )? {
                Some(factor) => factor,
                None => return Ok(false),
            }
        }
    };
    fgraph.add_factor(factor);
    Ok(true)
}

/// A plane factor in the arity its fixed variables call for (`None` when
/// both are fixed).
fn plane_factor<M, const N: usize>(
    model: M,
    pose: u32,
    plane: u32,
    values: &Values,
    fixed: &BTreeSet<Key>,
    noise: GaussianNoise<N>,
    kernel: RobustKernel,
) -> Result<Option<Factor>>
where
    M: PlaneModel<DimOut = factrs::linalg::Const<N>>,
{
    let factor = match (
        fixed.contains(&Key::Pose(pose)),
        fixed.contains(&Key::Plane(plane)),
    ) {
        (true, true) => return Ok(None),
        (false, false) => finish(
            FactorBuilder::<N>::new2(PoseAndPlane { model }, X(pose), L(plane)),
            noise,
            kernel,
        ),
        (true, false) => {
            let res = PlaneOnly {
                model,
                pose: to_se3(values.pose(pose)?),
            };
            finish(FactorBuilder::<N>::new1(res, L(plane)), noise, kernel)
        }
        (false, true) => {
            let res = PoseOnly {
                model,
                plane: to_plane(values.plane(plane)?),
            };
            finish(FactorBuilder::<N>::new1(res, X(pose)), noise, kernel)
        }
    };
    Ok(Some(factor))
}

/// Finish a factor with its noise and the factrs kernel with the same
/// `½ ρ` (factrs' `loss`); no kernel is factrs' default `L2`.
fn finish<const N: usize>(
    builder: FactorBuilder<N>,
    noise: GaussianNoise<N>,
    kernel: RobustKernel,
) -> Factor {
    let builder = builder.noise(noise);
    match kernel {
        RobustKernel::None => builder.build(),
        RobustKernel::Huber { k } => builder.robust(Huber::new(k)).build(),
        RobustKernel::Cauchy { k } => builder.robust(Cauchy::new(k)).build(),
    }
}

/// Our `(ρ, φ)` square-root information as factrs' `(ω, v)` one: `S Pᵀ`,
/// i.e. column `k` of the result is column `(k + 3) mod 6` of `S`.
fn pose_noise(s: &Matrix6<f64>) -> GaussianNoise<6> {
    let m = FMatrix6::from_fn(|r, k| s[(r, (k + 3) % 6)]);
    GaussianNoise::<6>::from_matrix_sqrt_inf(m)
}

/// A 3×3 matrix across the nalgebra versions.
fn mat3(s: &Matrix3<f64>) -> FMatrix3 {
    FMatrix3::from_fn(|r, k| s[(r, k)])
}

fn plane_to_plane(f: &PlaneObservation) -> PlaneToPlaneModel {
    let n = f.measured.normal;
    PlaneToPlaneModel {
        normal: [n.x, n.y, n.z],
        d: f.measured.d,
    }
}

/// The scatter model with `Lᵀ = Λ^½ Vᵀ` (`C = V Λ Vᵀ`), as our factor.
fn point_to_plane(f: &PointToPlane) -> Result<PointToPlaneModel> {
    let eig = SymmetricEigen::new(0.5 * (f.scatter + f.scatter.transpose()));
    let lt = Matrix3::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt()))
        * eig.eigenvectors.transpose();
    if !lt.iter().all(|v| v.is_finite()) || !(f.count >= 1.0) {
        return Err(Error::Input(
            "point_to_plane: scatter or count is not usable".into(),
        ));
    }
    let c = f.centroid;
    Ok(PointToPlaneModel {
        sqrt_count: f.count.sqrt(),
        centroid: [c.x, c.y, c.z],
        sqrt_scatter_t: [
            [lt[(0, 0)], lt[(0, 1)], lt[(0, 2)]],
            [lt[(1, 0)], lt[(1, 1)], lt[(1, 2)]],
            [lt[(2, 0)], lt[(2, 1)], lt[(2, 2)]],
        ],
    })
}

/// Our pose as a factrs `SE3` (quaternion `xyzw` and translation).
pub fn to_se3(x: &Isometry3<f64>) -> SE3 {
    let q = x.rotation.coords;
    let t = x.translation.vector;
    SE3::from_rot_trans(
        SO3::from_xyzw(q[0], q[1], q[2], q[3]),
        FVector3::new(t.x, t.y, t.z),
    )
}

/// A factrs `SE3` as our pose (quaternion renormalised).
pub fn from_se3(x: &SE3) -> Isometry3<f64> {
    let q = &x.rot().xyzw;
    let t = x.xyz();
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
    )
}

/// Our landmark as a factrs plane.
pub fn to_plane(p: &PlaneVar) -> FactrsPlane {
    FactrsPlane::new(FVector3::new(p.normal.x, p.normal.y, p.normal.z), p.d)
}

/// A factrs plane as our landmark; an error for a tangent element or a
/// degenerate normal.
pub fn from_plane(p: &FactrsPlane) -> Result<PlaneVar> {
    if p.tangent {
        return Err(Error::Input(
            "factrs returned a plane update, not a plane".into(),
        ));
    }
    PlaneVar::new(
        nalgebra::Vector3::new(p.normal.x, p.normal.y, p.normal.z),
        p.d,
    )
    .ok_or_else(|| Error::Input("factrs returned a degenerate plane".into()))
}

/// `initial` with the free variables replaced by factrs' results.
pub(super) fn convert_back(
    initial: &Values,
    fvalues: &FValues,
    free: &BTreeSet<Key>,
) -> Result<Values> {
    let mut out = initial.clone();
    for &key in free {
        let missing = || Error::Input(format!("factrs result lacks variable {key}"));
        match key {
            Key::Pose(id) => {
                let x: &SE3 = fvalues.get(X(id)).ok_or_else(missing)?;
                out.poses.insert(id, from_se3(x));
            }
            Key::Plane(id) => {
                let p: &FactrsPlane = fvalues.get(L(id)).ok_or_else(missing)?;
                out.planes.insert(id, from_plane(p)?);
            }
        }
    }
    crate::backend::graph::check_finite(&out)?;
    Ok(out)
}
