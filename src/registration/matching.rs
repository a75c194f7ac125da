//! Frame-to-frame plane matching by the paper's four similarity criteria.
//!
//! Every pair of planes of the same kind is tested (at most 25 ordinary
//! planes per frame, so all pairs are cheap):
//!
//! 1. normal cosine `n_s·n_t > min_normal_cos` (paper: 0.8);
//! 2. offset difference `|d_s − d_t| < max_offset` (paper: 0.1 m);
//! 3. centroid distance `‖c_s − c_t‖ < max_centroid_distance`;
//! 4. area ratio `max(A_s, A_t) / min(A_s, A_t) < max_area_ratio` (paper: 1.5).
//!
//! Criterion 3: the paper defines the centroid criterion as the *squared*
//! distance `‖c_s − c_t‖²` with threshold 0.5. We state thresholds in
//! metres: the criterion here is the plain distance, and the paper's
//! literal rule is `max_centroid_distance = √0.5 ≈ 0.71` m (what
//! `configs/paper.toml` sets).
//!
//! The criteria assume both frames are expressed close to each other. The
//! source planes are first moved by a prior transform (the motion model's
//! prediction of the relative pose; identity reproduces the paper); the
//! returned pairs hold the source planes as they were.

use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

use super::Correspondence;
use crate::frontend::FramePlane;
use crate::geometry::Plane;
use crate::io::PlaneKind;

/// The four matching thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatchCriteria {
    /// Normals must have a larger cosine (paper: 0.8).
    pub min_normal_cos: f64,
    /// Offsets must differ by less, m (paper: 0.1).
    pub max_offset: f64,
    /// Centroids must be closer, m (paper: squared distance < 0.5, i.e.
    /// 0.71 m).
    pub max_centroid_distance: f64,
    /// The larger area over the smaller must be below this (paper: 1.5).
    pub max_area_ratio: f64,
}

impl Default for MatchCriteria {
    /// [`FRAME_MATCHING`](crate::slam::tracker::FRAME_MATCHING).
    fn default() -> Self {
        crate::slam::tracker::FRAME_MATCHING
    }
}

impl MatchCriteria {
    /// Whether a source plane (plane, centroid, area; already moved into
    /// the target frame) matches a target plane.
    pub fn accepts(
        &self,
        source: (&Plane, &Point3<f64>, f64),
        target: (&Plane, &Point3<f64>, f64),
    ) -> bool {
        let (ps, cs, a_s) = source;
        let (pt, ct, a_t) = target;
        let (lo, hi) = if a_s <= a_t { (a_s, a_t) } else { (a_t, a_s) };
        ps.normal_cosine(pt) > self.min_normal_cos
            && (ps.d - pt.d).abs() < self.max_offset
            && (cs - ct).norm() < self.max_centroid_distance
            && lo > 0.0
            && hi / lo < self.max_area_ratio
    }
}

/// All pairs (source, target) of the same kind that meet `criteria` once
/// the source planes are moved by `prior` (source frame to target frame).
/// Pairs are in (source, target) index order; a plane may appear in
/// several pairs (the mismatch rejector sorts them out).
pub fn match_planes(
    source: &[FramePlane],
    target: &[FramePlane],
    prior: &Isometry3<f64>,
    criteria: &MatchCriteria,
) -> Vec<Correspondence> {
    let mut out = Vec::new();
    for (i, s) in source.iter().enumerate() {
        let moved = s.plane.transformed(prior);
        let centroid = prior * s.centroid;
        for (j, t) in target.iter().enumerate() {
            if s.kind != t.kind {
                continue;
            }
            if criteria.accepts((&moved, &centroid, s.area), (&t.plane, &t.centroid, t.area)) {
                out.push(Correspondence {
                    source: s.plane,
                    target: t.plane,
                    ground: s.kind == PlaneKind::Ground,
                    source_index: i,
                    target_index: j,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn wall(d: f64) -> Plane {
        Plane::new(Vector3::new(-1.0, 0.0, 0.0), d).unwrap()
    }

    #[test]
    fn each_criterion_rejects_on_its_own() {
        let c = MatchCriteria::default();
        let p = wall(3.0);
        let at = |x: f64, y: f64| Point3::new(x, y, 0.0);
        let base = (&p, &at(3.0, 0.0), 4.0);
        assert!(c.accepts(base, (&wall(3.05), &at(3.05, 0.3), 5.0)));
        // 1. normal: 40 degrees apart (cos 0.77 < 0.8).
        let tilted = Plane::new(
            Vector3::new(-40f64.to_radians().cos(), 40f64.to_radians().sin(), 0.0),
            3.0,
        )
        .unwrap();
        assert!(!c.accepts(base, (&tilted, &at(3.0, 0.0), 4.0)));
        // 2. offset 0.12 m.
        assert!(!c.accepts(base, (&wall(3.12), &at(3.12, 0.0), 4.0)));
        // 3. centroid 0.75 m away (> 0.71, the paper's squared 0.5).
        assert!(!c.accepts(base, (&wall(3.0), &at(3.0, 0.75), 4.0)));
        assert!(c.accepts(base, (&wall(3.0), &at(3.0, 0.70), 4.0)));
        // 4. area ratio 1.5.
        assert!(!c.accepts(base, (&wall(3.0), &at(3.0, 0.0), 6.0)));
        assert!(!c.accepts(base, (&wall(3.0), &at(3.0, 0.0), 0.0)));
    }
}
