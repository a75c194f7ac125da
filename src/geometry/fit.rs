//! Plane fitting: total least squares (PCA) and RANSAC with a least-squares
//! refit and inlier reselection (the PCL `SACSegmentation` semantics the
//! paper's thresholds were tuned with).

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

use super::Plane;
use crate::rng::SplitMix64;

/// Total-least-squares plane through `points` (the smallest principal axis of
/// their scatter). Returns the plane and the eigenvalues of the covariance,
/// ascending; `None` for fewer than 3 points or a degenerate (collinear) set.
pub fn fit_plane<I>(points: I) -> Option<(Plane, [f64; 3])>
where
    I: IntoIterator<Item = Point3<f64>>,
    I::IntoIter: Clone,
{
    let it = points.into_iter();
    let mut n = 0usize;
    let mut sum = Vector3::zeros();
    for p in it.clone() {
        sum += p.coords;
        n += 1;
    }
    if n < 3 {
        return None;
    }
    let mean = sum / n as f64;
    let mut cov = Matrix3::zeros();
    for p in it {
        let r = p.coords - mean;
        cov += r * r.transpose();
    }
    cov /= n as f64;
    plane_from_moments(&Point3::from(mean), &cov)
}

/// The plane through `mean` normal to the smallest principal axis of the
/// covariance `cov`, with its eigenvalues ascending; `None` when the
/// points are collinear or coincident.
fn plane_from_moments(mean: &Point3<f64>, cov: &Matrix3<f64>) -> Option<(Plane, [f64; 3])> {
    let eig = SymmetricEigen::new(*cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let values = [
        eig.eigenvalues[order[0]],
        eig.eigenvalues[order[1]],
        eig.eigenvalues[order[2]],
    ];
    // Collinear or coincident points do not define a plane.
    if !(values[1] > 1e-12) {
        return None;
    }
    let normal = eig.eigenvectors.column(order[0]).into_owned();
    let plane = Plane::from_point_normal(mean, &normal)?;
    Some((plane, values))
}

/// A weighted total-least-squares plane fitted incrementally: the sums of
/// the points' weights, positions and outer products (relative to a
/// reference point near them, against round-off), so a surface sampled
/// over a whole sequence is fitted without keeping its points. Sums added
/// in the same order give the same plane.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneSums {
    reference: Point3<f64>,
    weight: f64,
    count: u64,
    sum: Vector3<f64>,
    outer: Matrix3<f64>,
}

impl PlaneSums {
    /// Empty sums about `reference`.
    pub fn new(reference: Point3<f64>) -> Self {
        Self {
            reference,
            weight: 0.0,
            count: 0,
            sum: Vector3::zeros(),
            outer: Matrix3::zeros(),
        }
    }

    /// Add the point `p` with weight `w` (positive).
    #[inline]
    pub fn add(&mut self, p: &Point3<f64>, w: f64) {
        let d = p - self.reference;
        self.weight += w;
        self.count += 1;
        self.sum += d * w;
        self.outer += d * d.transpose() * w;
    }

    /// Add the sums of other points, kept about the same reference.
    pub fn merge(&mut self, other: &Self) {
        debug_assert_eq!(self.reference, other.reference);
        self.weight += other.weight;
        self.count += other.count;
        self.sum += other.sum;
        self.outer += other.outer;
    }

    /// Points added.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The weighted mean of the points, `None` without any.
    pub fn centroid(&self) -> Option<Point3<f64>> {
        (self.weight > 0.0).then(|| self.reference + self.sum / self.weight)
    }

    /// The weighted total-least-squares plane, with the eigenvalues of the
    /// weighted covariance ascending (as [`fit_plane`]); `None` for fewer
    /// than 3 points or a degenerate set.
    pub fn fit(&self) -> Option<(Plane, [f64; 3])> {
        if self.count < 3 || !(self.weight > 0.0) {
            return None;
        }
        let mean = self.sum / self.weight;
        let cov = self.outer / self.weight - mean * mean.transpose();
        plane_from_moments(&(self.reference + mean), &cov)
    }
}

/// RANSAC parameters (PCL names in brackets). A configuration section
/// `[*.ransac]` states only `distance`; each stage's iterations, probability
/// and refit are a constant beside it (e.g. `reflect::detector::RANSAC`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RansacParams {
    /// Inlier distance threshold in metres (PCL: `distance_threshold`).
    pub distance: f64,
    /// Maximum number of iterations (PCL: `max_iterations`).
    pub max_iterations: usize,
    /// Desired probability of drawing an outlier-free sample (PCL: `probability`);
    /// iterations stop early once it is reached.
    pub probability: f64,
    /// Refit the best model by least squares on its inliers and reselect the
    /// inliers with the refined plane (PCL: `optimize_coefficients`).
    pub refit: bool,
}

/// The keys of a `[*.ransac]` configuration section.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RansacKeys {
    /// Inlier distance threshold, m.
    distance: f64,
}

/// Serialise RANSAC parameters as their configuration section: the inlier
/// distance alone (`serialize_with`).
pub fn serialize_distance<S: serde::Serializer>(
    params: &RansacParams,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    RansacKeys {
        distance: params.distance,
    }
    .serialize(serializer)
}

/// Read a `[*.ransac]` configuration section (its `distance`) into `stage`'s
/// RANSAC parameters (for a stage's `deserialize_with`).
pub fn deserialize_distance<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
    stage: RansacParams,
) -> Result<RansacParams, D::Error> {
    let keys = RansacKeys::deserialize(deserializer)?;
    Ok(RansacParams {
        distance: keys.distance,
        ..stage
    })
}

/// A fitted plane with the indices (into the input slice) of its inliers.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneFit {
    /// The plane.
    pub plane: Plane,
    /// Inlier indices into the input slice, ascending.
    pub inliers: Vec<u32>,
}

/// RANSAC plane fit over `points`. Deterministic for a given `rng` state.
/// Returns `None` when fewer than 3 points are given or no sample defines a
/// plane.
pub fn ransac_plane(
    points: &[Point3<f64>],
    params: &RansacParams,
    rng: &mut SplitMix64,
) -> Option<PlaneFit> {
    let n = points.len();
    if n < 3 {
        return None;
    }
    let mut best: Option<(Plane, usize)> = None;
    let mut needed = params.max_iterations as f64;
    let mut iter = 0usize;
    while (iter as f64) < needed.min(params.max_iterations as f64) {
        iter += 1;
        let (a, b, c) = (rng.below(n), rng.below(n), rng.below(n));
        if a == b || b == c || a == c {
            continue;
        }
        let normal = (points[b] - points[a]).cross(&(points[c] - points[a]));
        let Some(plane) = Plane::from_point_normal(&points[a], &normal) else {
            continue;
        };
        let count = count_inliers(points, &plane, params.distance);
        if best.is_none_or(|(_, c)| count > c) {
            best = Some((plane, count));
            // Adaptive iteration count (as PCL): k = log(1-p) / log(1-w^3).
            let w = count as f64 / n as f64;
            let denom = (1.0 - w.powi(3)).max(1e-12).ln();
            if denom < 0.0 {
                needed = ((1.0 - params.probability).ln() / denom).ceil().max(1.0);
            }
        }
    }
    let (mut plane, _) = best?;
    if params.refit {
        let inliers = select_inliers(points, &plane, params.distance);
        if let Some((refined, _)) = fit_plane(inliers.iter().map(|&i| points[i as usize])) {
            plane = refined;
        }
    }
    let inliers = select_inliers(points, &plane, params.distance);
    Some(PlaneFit { plane, inliers })
}

fn count_inliers(points: &[Point3<f64>], plane: &Plane, distance: f64) -> usize {
    points
        .iter()
        .filter(|p| plane.signed_distance(p).abs() <= distance)
        .count()
}

/// Remove from `items` the entries at `positions` (indices into `items`, as
/// the inliers of a fit on `items`), keeping the order of the rest: the
/// "remove the inliers, fit again" step of multi-plane RANSAC.
pub fn remove_positions<T>(items: &mut Vec<T>, positions: &[u32]) {
    let mut drop = vec![false; items.len()];
    for &k in positions {
        if let Some(d) = drop.get_mut(k as usize) {
            *d = true;
        }
    }
    let mut k = 0;
    items.retain(|_| {
        k += 1;
        !drop[k - 1]
    });
}

/// Indices of the points within `distance` of `plane`.
pub fn select_inliers(points: &[Point3<f64>], plane: &Plane, distance: f64) -> Vec<u32> {
    points
        .iter()
        .enumerate()
        .filter(|(_, p)| plane.signed_distance(p).abs() <= distance)
        .map(|(i, _)| i as u32)
        .collect()
}
