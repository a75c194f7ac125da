//! A convex boundary fitted to evidence as a linear program.
//!
//! The polygon has a fixed set of edge directions: the principal axes of the
//! reflective evidence and the diagonals between them (8 half-planes
//! `a_k · x <= b_k`). Only the offsets `b_k` are unknown, which makes the fit
//! convex: every reflective (inside) sample must satisfy all half-planes, up
//! to a hinge slack `ξ_i`; every opaque (outside) sample must violate the
//! half-plane of the direction it lies beyond, up to a slack `η_j`; a small
//! regularizer on `Σ b_k` (the polygon's mean width) keeps it tight where no
//! evidence speaks:
//!
//! ```text
//! minimise   λ Σ_k b_k + w_in Σ_i ξ_i + w_out Σ_j η_j
//! subject to a_k · x_i + h <= b_k + ξ_i      (inside samples, every k)
//!            a_k(j) · x_j - h >= b_k(j) - η_j  (outside samples)
//!            ξ, η >= 0
//! ```
//! with `h` half a grid cell, so whole cells are covered or excluded. It is
//! an LP solved by clarabel's interior-point method in milliseconds
//! ([`BoundarySolver::JointLp`]).
//!
//! Counting an inside sample once per half-plane it lies beyond (a sum of
//! per-edge slacks instead of their maximum) makes the problem separable:
//! each offset `b_k` then minimises a 1-D convex piecewise-linear function,
//! `λ b + w_in Σ_i (a_k·x_i + h - b)⁺ + w_out Σ_j (b - a_k·x_j + h)⁺`, whose
//! minimum is a weighted quantile of the samples' projections, found exactly
//! by one sort ([`BoundarySolver::PerEdge`], microseconds instead of
//! milliseconds). The two differ only at corners, where a sample beyond two
//! edges costs twice.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};
use nalgebra::{Matrix2, Point2, SymmetricEigen, Vector2};
use serde::{Deserialize, Serialize};

use crate::geometry::ConvexPolygon;

/// Weights of the boundary LP (a method constant, [`FIT`], in every
/// configuration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryFitParams {
    /// Cost of leaving an inside (reflective) sample outside, per metre.
    pub inside_weight: f64,
    /// Cost of covering an outside (opaque) sample, per metre.
    pub outside_weight: f64,
    /// Cost per metre of the sum of the offsets (the polygon's size).
    pub regularizer: f64,
    /// How the offsets are found.
    pub solver: BoundarySolver,
}

/// The solver of the boundary fit (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundarySolver {
    /// One LP over all offsets, an inside sample's slack shared by every
    /// edge (clarabel).
    JointLp,
    /// Each offset alone, exactly, by a weighted-quantile sweep.
    PerEdge,
}

/// The boundary fit of every configuration: inside and outside samples
/// weigh 1 per metre each, the polygon's size 0.05 per metre, each offset
/// found exactly by the per-edge sweep.
pub const FIT: BoundaryFitParams = BoundaryFitParams {
    inside_weight: 1.0,
    outside_weight: 1.0,
    regularizer: 0.05,
    solver: BoundarySolver::PerEdge,
};

impl Default for BoundaryFitParams {
    /// [`FIT`].
    fn default() -> Self {
        FIT
    }
}

/// The 8 edge normals: the principal axes of `inside` and the diagonals.
pub fn edge_directions(inside: &[Point2<f64>]) -> [Vector2<f64>; 8] {
    let n = inside.len().max(1) as f64;
    let mean = inside.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / n;
    let cov = inside.iter().fold(Matrix2::zeros(), |a, p| {
        let r = p.coords - mean;
        a + r * r.transpose()
    });
    let eig = SymmetricEigen::new(cov);
    let k = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        0
    } else {
        1
    };
    let axis = eig.eigenvectors.column(k);
    let theta0 = if axis.norm() > 0.0 && axis[0].is_finite() && axis[1].is_finite() {
        axis[1].atan2(axis[0])
    } else {
        0.0
    };
    std::array::from_fn(|k| {
        let t = theta0 + k as f64 * std::f64::consts::FRAC_PI_4;
        Vector2::new(t.cos(), t.sin())
    })
}

/// Fit the convex boundary of `inside` samples against `outside` samples
/// (chart coordinates, `half_cell` the half size of the cells they stand
/// for). `None` when there are no inside samples, the LP fails, or the
/// polygon is empty.
pub fn fit_boundary(
    inside: &[Point2<f64>],
    outside: &[Point2<f64>],
    half_cell: f64,
    params: &BoundaryFitParams,
) -> Option<ConvexPolygon> {
    if inside.is_empty()
        || !inside
            .iter()
            .chain(outside)
            .all(|p| p.x.is_finite() && p.y.is_finite())
    {
        return None;
    }
    let dirs = edge_directions(inside);
    // The inside extent along each direction decides which half-plane an
    // outside sample is assigned to: the one it lies farthest beyond.
    let extent: Vec<f64> = dirs
        .iter()
        .map(|a| {
            inside
                .iter()
                .map(|x| a.dot(&x.coords))
                .fold(f64::NEG_INFINITY, f64::max)
        })
        .collect();
    let assigned: Vec<usize> = outside
        .iter()
        .map(|x| {
            (0..dirs.len())
                .max_by(|&p, &q| {
                    (dirs[p].dot(&x.coords) - extent[p])
                        .total_cmp(&(dirs[q].dot(&x.coords) - extent[q]))
                })
                .unwrap_or(0)
        })
        .collect();
    let b = match params.solver {
        BoundarySolver::JointLp => joint_lp(inside, outside, &dirs, &assigned, half_cell, params)?,
        BoundarySolver::PerEdge => per_edge(inside, outside, &dirs, &assigned, half_cell, params)?,
    };
    // The polygon: a box around the data clipped by every half-plane.
    let (mut lo, mut hi) = (
        Point2::new(f64::INFINITY, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for x in inside {
        lo = Point2::new(lo.x.min(x.x), lo.y.min(x.y));
        hi = Point2::new(hi.x.max(x.x), hi.y.max(x.y));
    }
    let pad = 10.0 + 10.0 * half_cell;
    let mut poly = ConvexPolygon::rectangle(
        Point2::new(lo.x - pad, lo.y - pad),
        Point2::new(hi.x + pad, hi.y + pad),
    );
    for (a, &bk) in dirs.iter().zip(&b) {
        poly = poly.clip(a, bk);
        if poly.is_empty() {
            return None;
        }
    }
    Some(poly)
}

/// The offsets from the joint LP (clarabel); `None` when it fails.
fn joint_lp(
    inside: &[Point2<f64>],
    outside: &[Point2<f64>],
    dirs: &[Vector2<f64>; 8],
    assigned: &[usize],
    half_cell: f64,
    params: &BoundaryFitParams,
) -> Option<[f64; 8]> {
    let (nk, ni, nj) = (dirs.len(), inside.len(), outside.len());
    let nvar = nk + ni + nj;
    // Variables: [b_0..b_7, ξ_0.., η_0..]; rows "A x <= rhs" (nonnegative cone).
    let (mut rows, mut cols, mut vals, mut rhs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut row = 0usize;
    for (i, x) in inside.iter().enumerate() {
        for (k, a) in dirs.iter().enumerate() {
            // a·x + h - b_k - ξ_i <= 0
            rows.extend([row, row]);
            cols.extend([k, nk + i]);
            vals.extend([-1.0, -1.0]);
            rhs.push(-(a.dot(&x.coords) + half_cell));
            row += 1;
        }
    }
    for (j, (x, &k)) in outside.iter().zip(assigned).enumerate() {
        // b_k - η_j <= a·x - h
        rows.extend([row, row]);
        cols.extend([k, nk + ni + j]);
        vals.extend([1.0, -1.0]);
        rhs.push(dirs[k].dot(&x.coords) - half_cell);
        row += 1;
    }
    for v in nk..nvar {
        // slack >= 0
        rows.push(row);
        cols.push(v);
        vals.push(-1.0);
        rhs.push(0.0);
        row += 1;
    }
    let a = CscMatrix::new_from_triplets(row, nvar, rows, cols, vals);
    let p = CscMatrix::<f64>::zeros((nvar, nvar));
    let mut q = vec![params.regularizer; nk];
    q.extend(std::iter::repeat_n(params.inside_weight, ni));
    q.extend(std::iter::repeat_n(params.outside_weight, nj));
    let cones: [SupportedConeT<f64>; 1] = [NonnegativeConeT(row)];
    // Offsets in metres only need millimetre accuracy: looser tolerances than
    // clarabel's defaults halve the iterations.
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(100)
        .tol_gap_abs(1e-6)
        .tol_gap_rel(1e-6)
        .tol_feas(1e-6)
        .build()
        .ok()?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &rhs, &cones, settings).ok()?;
    solver.solve();
    if !matches!(
        solver.solution.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    ) {
        return None;
    }
    solver.solution.x[..nk].try_into().ok()
}

/// The offsets of the separable problem, each exactly: the derivative of
/// `λ b + w_in Σ (c_i - b)⁺ + w_out Σ (b - e_j)⁺` is `λ - w_in #{c_i > b} +
/// w_out #{e_j < b}`, nondecreasing in `b`; the minimum is at the first
/// breakpoint where it turns non-negative. `None` when some offset is
/// unbounded below (the regularizer outweighs all inside samples).
fn per_edge(
    inside: &[Point2<f64>],
    outside: &[Point2<f64>],
    dirs: &[Vector2<f64>; 8],
    assigned: &[usize],
    half_cell: f64,
    params: &BoundaryFitParams,
) -> Option<[f64; 8]> {
    let mut b = [0.0; 8];
    // (breakpoint, derivative increase when b moves past it)
    let mut breaks: Vec<(f64, f64)> = Vec::with_capacity(inside.len() + outside.len());
    for (k, a) in dirs.iter().enumerate() {
        breaks.clear();
        breaks.extend(
            inside
                .iter()
                .map(|x| (a.dot(&x.coords) + half_cell, params.inside_weight)),
        );
        breaks.extend(
            outside
                .iter()
                .zip(assigned)
                .filter(|(_, &kj)| kj == k)
                .map(|(x, _)| (a.dot(&x.coords) - half_cell, params.outside_weight)),
        );
        breaks.sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
        let mut slope = params.regularizer - params.inside_weight * inside.len() as f64;
        if slope >= 0.0 {
            return None;
        }
        let mut best = None;
        for &(at, step) in &breaks {
            slope += step;
            if slope >= 0.0 {
                best = Some(at);
                break;
            }
        }
        b[k] = best?;
    }
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cell centres of a `cell`-spaced grid over [x0, x1] × [y0, y1].
    fn cells(x0: f64, x1: f64, y0: f64, y1: f64, cell: f64) -> Vec<Point2<f64>> {
        let mut v = Vec::new();
        let mut y = y0 + cell / 2.0;
        while y < y1 {
            let mut x = x0 + cell / 2.0;
            while x < x1 {
                v.push(Point2::new(x, y));
                x += cell;
            }
            y += cell;
        }
        v
    }

    #[test]
    fn recovers_a_rectangle_within_the_grid_resolution() {
        let cell = 0.2;
        let inside = cells(0.0, 3.0, 0.0, 2.0, cell);
        let outside: Vec<_> = cells(-1.0, 4.0, -1.0, 3.0, cell)
            .into_iter()
            .filter(|p| !(p.x > 0.0 && p.x < 3.0 && p.y > 0.0 && p.y < 2.0))
            .collect();
        let truth = ConvexPolygon::rectangle(Point2::new(0.0, 0.0), Point2::new(3.0, 2.0));
        for params in both_solvers() {
            let poly = fit_boundary(&inside, &outside, cell / 2.0, &params).unwrap();
            assert!(
                (poly.area() - 6.0).abs() < 3.0 * cell,
                "area {}",
                poly.area()
            );
            assert!(
                poly.intersection_area(&truth) > 6.0 - 2.0 * cell * 5.0,
                "{:?}",
                poly.vertices()
            );
            for v in poly.vertices() {
                assert!(
                    truth.signed_distance(v) < cell,
                    "vertex {v} off the rectangle"
                );
            }
        }
    }

    #[test]
    fn opaque_samples_inside_the_hull_cut_the_boundary() {
        // Reflective evidence on an L shape; opaque evidence fills the notch.
        let cell = 0.2;
        let mut inside = cells(0.0, 4.0, 0.0, 1.0, cell);
        inside.extend(cells(0.0, 1.0, 1.0, 3.0, cell));
        let notch = cells(1.2, 4.0, 1.2, 3.0, cell);
        for params in both_solvers() {
            let poly = fit_boundary(&inside, &notch, cell / 2.0, &params).unwrap();
            let covered = notch.iter().filter(|p| poly.contains(p)).count();
            assert!(
                covered * 4 < notch.len(),
                "{:?}: {covered} of {} opaque cells covered",
                params.solver,
                notch.len()
            );
        }
    }

    #[test]
    fn per_edge_offsets_are_the_weighted_quantile() {
        // Inside samples at 0..10 along x (h = 0), no outside samples: the
        // derivative λ - #{c > b} turns non-negative at the sample where
        // fewer than λ samples remain beyond; with λ < 1 that is the last.
        let inside: Vec<_> = (0..10).map(|i| Point2::new(i as f64, 0.0)).collect();
        let dirs = edge_directions(&inside);
        let params = BoundaryFitParams::default();
        let b = per_edge(&inside, &[], &dirs, &[], 0.0, &params).unwrap();
        for (a, bk) in dirs.iter().zip(b) {
            let max = inside
                .iter()
                .map(|x| a.dot(&x.coords))
                .fold(f64::MIN, f64::max);
            assert!((bk - max).abs() < 1e-12, "offset {bk} vs extent {max}");
        }
        // A regularizer heavier than three samples leaves the outer three out.
        let heavy = BoundaryFitParams {
            regularizer: 3.5,
            ..params
        };
        let b = per_edge(&inside, &[], &dirs, &[], 0.0, &heavy).unwrap();
        let k = (0..8).find(|&k| (dirs[k].x - 1.0).abs() < 1e-9).unwrap();
        assert!((b[k] - 6.0).abs() < 1e-12, "offset {}", b[k]);
        // Heavier than all samples: unbounded, no boundary.
        let all = BoundaryFitParams {
            regularizer: 11.0,
            ..params
        };
        assert!(per_edge(&inside, &[], &dirs, &[], 0.0, &all).is_none());
    }

    fn both_solvers() -> [BoundaryFitParams; 2] {
        [BoundarySolver::JointLp, BoundarySolver::PerEdge].map(|solver| BoundaryFitParams {
            solver,
            ..BoundaryFitParams::default()
        })
    }

    #[test]
    fn empty_or_degenerate_evidence_gives_no_boundary() {
        for p in both_solvers() {
            assert!(fit_boundary(&[], &[Point2::new(0.0, 0.0)], 0.1, &p).is_none());
            assert!(fit_boundary(&[Point2::new(f64::NAN, 0.0)], &[], 0.1, &p).is_none());
            // One sample: a small polygon around it, not a panic.
            let one = fit_boundary(&[Point2::new(1.0, 1.0)], &[], 0.1, &p);
            assert!(one.is_none_or(|poly| poly.contains(&Point2::new(1.0, 1.0))));
        }
    }
}
