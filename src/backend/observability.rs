//! Unobservable directions, reported instead of hidden.
//!
//! For each pose, the 6×6 information its plane factors alone give,
//! `Σ J_xᵀ J_x` over the plane factors touching it, is eigen-decomposed; an
//! eigenvalue below `threshold × largest` marks a direction the planes do not
//! constrain (a corridor's axis: every wall normal is orthogonal to it). The
//! pose may still be fixed by odometry, but the report says it is riding on
//! odometry alone along that direction.

use nalgebra::{Matrix6, SymmetricEigen, Vector6};
use serde::Serialize;

use super::factors::{Factor, Linearization};
use super::graph::FactorGraph;
use super::variables::{Key, Values};
use crate::Result;

/// A pose with at least one direction its plane observations do not fix.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeakPose {
    /// The pose's id.
    pub pose: u32,
    /// Number of eigenvalues below the threshold (6 when no plane sees it).
    pub directions: usize,
    /// Smallest eigenvalue of the plane information block.
    pub min_eigenvalue: f64,
    /// Eigenvector of the smallest eigenvalue, `(ρ, φ)` order.
    pub weakest_direction: [f64; 6],
}

/// Summary over all poses.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ObservabilityReport {
    /// Relative eigenvalue threshold used.
    pub threshold: f64,
    /// Poses examined.
    pub poses: usize,
    /// Poses with at least one weak direction, by id.
    pub weak: Vec<WeakPose>,
}

/// Analyse the plane information of every pose at `values`.
pub fn analyse(
    graph: &FactorGraph,
    values: &Values,
    threshold: f64,
) -> Result<ObservabilityReport> {
    let mut info: std::collections::BTreeMap<u32, Matrix6<f64>> = values
        .poses
        .keys()
        .map(|&i| (i, Matrix6::zeros()))
        .collect();
    let mut lin = Linearization::default();
    for f in graph.factors.iter().filter(|f| f.factor.is_plane_factor()) {
        f.linearize(values, &mut lin)?;
        if let Some(Key::Pose(id)) = f.factor.keys().first() {
            let j = lin.jacobians[0].rows(0, lin.dim);
            if let Some(m) = info.get_mut(id) {
                *m += j.transpose() * j;
            }
        }
    }
    let mut weak = Vec::new();
    for (&pose, m) in &info {
        let eig = SymmetricEigen::new(*m);
        let max = eig.eigenvalues.max();
        let k = eig.eigenvalues.imin();
        let min = eig.eigenvalues[k];
        let limit = threshold * max.max(0.0);
        let directions = if max > 0.0 {
            eig.eigenvalues.iter().filter(|&&l| l <= limit).count()
        } else {
            6
        };
        if directions > 0 {
            let v: Vector6<f64> = eig.eigenvectors.column(k).into_owned();
            weak.push(WeakPose {
                pose,
                directions,
                min_eigenvalue: min,
                weakest_direction: v.into(),
            });
        }
    }
    Ok(ObservabilityReport {
        threshold,
        poses: info.len(),
        weak,
    })
}
