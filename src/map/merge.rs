//! Fusing plane observations into the map.

use serde::{Deserialize, Serialize};

use super::landmark::{hull_on_plane, Landmark, PlaneMap, PlaneObservation};
use crate::geometry::{ConvexPolygon, Plane, PlaneChart};

/// Fuses observations into a [`PlaneMap`]. Implementations are selected by
/// name ([`super::MapParams::merger`], no key).
pub trait MapMerger: Send + Sync {
    /// The name this merger is selected by.
    fn name(&self) -> &'static str;

    /// Fuse `obs` into `map`: update the landmark it matches or add a new one.
    /// Returns the landmark's index in `map.landmarks`.
    fn merge(&self, map: &mut PlaneMap, obs: &PlaneObservation) -> usize;

    /// Fuse `obs` into the landmark at `index` of `map`, whose match was
    /// decided elsewhere (the SLAM tracker's scan-to-map association).
    /// An index out of range adds a new landmark instead. Returns the
    /// landmark's index.
    fn fuse(&self, map: &mut PlaneMap, index: usize, obs: &PlaneObservation) -> usize;
}

/// Matching and weighting thresholds of the paper's merger.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MergeParams {
    /// Normals match when `1 - cos(angle) <` this (paper: 0.2, about 37 deg).
    pub max_one_minus_cos: f64,
    /// Offsets match when `|d_new - d_map| <` this, m (paper: 0.1).
    pub max_offset: f64,
    /// Weight of the stored plane after its first observation: [`SECOND_WEIGHT`].
    #[serde(skip, default = "second_weight")]
    pub second_weight: f64,
    /// Cap on the stored plane's weight: [`MAX_WEIGHT`].
    #[serde(skip, default = "max_weight")]
    pub max_weight: f64,
}

/// The paper's weighted average: weight of the stored plane after its first
/// observation (then its observation count), against 1 for the new one.
/// Also the average back-end's (`backend::average`).
pub const SECOND_WEIGHT: f64 = 3.0;

/// The paper's cap on the stored plane's weight in the weighted average.
pub const MAX_WEIGHT: f64 = 10.0;

fn second_weight() -> f64 {
    SECOND_WEIGHT
}

fn max_weight() -> f64 {
    MAX_WEIGHT
}

impl Default for MergeParams {
    /// `[map.merge]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("map.merge")
    }
}

/// The paper's merger: match by normal, offset and hull overlap (first match
/// wins); fuse by a weighted average of the plane parameters (new 1, stored 3
/// after one observation, then its count, capped at 10) and the hull of the
/// union of both boundaries projected onto the fused plane. Observations are
/// matched only to landmarks of the same kind (reflective, ordinary or
/// ground: the same rules hold for all three) and orientation (planes face
/// the sensors that saw them).
#[derive(Debug, Clone, Default)]
pub struct WeightedAverageMerger {
    params: MergeParams,
}

impl WeightedAverageMerger {
    /// A merger with the given thresholds.
    pub fn new(params: MergeParams) -> Self {
        Self { params }
    }

    /// Whether `obs` matches landmark `l`.
    pub fn matches(&self, l: &Landmark, obs: &PlaneObservation) -> bool {
        let p = &self.params;
        if l.kind != obs.kind
            || 1.0 - l.plane.normal_cosine(&obs.plane) >= p.max_one_minus_cos
            || (l.plane.d - obs.plane.d).abs() >= p.max_offset
        {
            return false;
        }
        // Overlap (the paper's test): the hulls are disjoint when the hull of
        // their union is larger than both areas together.
        let chart = PlaneChart::of(&l.plane);
        let to_2d = |pts: &[nalgebra::Point3<f64>]| -> Vec<_> {
            pts.iter().map(|q| chart.to_2d(q)).collect()
        };
        let a = ConvexPolygon::hull(&to_2d(&l.boundary));
        let b = ConvexPolygon::hull(&to_2d(&obs.boundary));
        a.union_hull(&b).area() <= a.area() + b.area()
    }

    fn fuse_landmark(&self, l: &mut Landmark, obs: &PlaneObservation) {
        let p = &self.params;
        let stored = if l.observations == 1 {
            p.second_weight
        } else {
            (l.observations as f64).min(p.max_weight)
        };
        let n = obs.plane.normal + l.plane.normal * stored;
        let d = obs.plane.d + l.plane.d * stored;
        // (a n_new + b n_map) / (a + b), normalised (the offset scales with it).
        if let Some(fused) = Plane::new(n / (1.0 + stored), d / (1.0 + stored)) {
            l.plane = fused;
        }
        let points = l.boundary.iter().chain(&obs.boundary).copied();
        let hull = hull_on_plane(&l.plane, points);
        if hull.len() >= 3 {
            l.boundary = hull;
        }
        l.observations += 1;
        l.first_frame = l.first_frame.min(obs.frame);
        l.last_frame = l.last_frame.max(obs.frame);
    }
}

impl MapMerger for WeightedAverageMerger {
    fn name(&self) -> &'static str {
        "weighted-average"
    }

    fn merge(&self, map: &mut PlaneMap, obs: &PlaneObservation) -> usize {
        if let Some(k) = map.landmarks.iter().position(|l| self.matches(l, obs)) {
            self.fuse_landmark(&mut map.landmarks[k], obs);
            return k;
        }
        let id = map.next_id();
        map.landmarks.push(Landmark::new(id, obs));
        map.landmarks.len() - 1
    }

    fn fuse(&self, map: &mut PlaneMap, index: usize, obs: &PlaneObservation) -> usize {
        match map.landmarks.get_mut(index) {
            Some(l) => {
                self.fuse_landmark(l, obs);
                index
            }
            None => {
                let id = map.next_id();
                map.landmarks.push(Landmark::new(id, obs));
                map.landmarks.len() - 1
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::PlaneKind;
    use nalgebra::{Point3, Vector3};

    fn obs(x0: f64, x1: f64, d: f64, frame: usize) -> PlaneObservation {
        // A wall x = -d (normal +x), spanning y in [x0, x1], z in [0, 2].
        let plane = Plane::new(Vector3::x(), d).unwrap();
        PlaneObservation {
            kind: PlaneKind::Reflective,
            plane,
            boundary: vec![
                Point3::new(-d, x0, 0.0),
                Point3::new(-d, x1, 0.0),
                Point3::new(-d, x1, 2.0),
                Point3::new(-d, x0, 2.0),
            ],
            frame,
        }
    }

    #[test]
    fn overlapping_observations_fuse_and_disjoint_ones_do_not() {
        let m = WeightedAverageMerger::default();
        let mut map = PlaneMap::new();
        assert_eq!(m.merge(&mut map, &obs(0.0, 2.0, 5.0, 0)), 0);
        assert_eq!(m.merge(&mut map, &obs(1.0, 3.0, 5.04, 1)), 0);
        let l = &map.landmarks[0];
        assert_eq!(l.observations, 2);
        // Weighted average: (5.04 + 3 * 5.0) / 4.
        assert!((l.plane.d - 5.01).abs() < 1e-9, "{}", l.plane.d);
        assert!((l.area() - 6.0).abs() < 1e-6, "{}", l.area());
        // Far away on the same plane: a separate landmark.
        assert_eq!(m.merge(&mut map, &obs(10.0, 12.0, 5.0, 2)), 1);
        // Same place, offset too different: a separate landmark.
        assert_eq!(m.merge(&mut map, &obs(0.0, 2.0, 5.3, 3)), 2);
        // Opposite orientation (seen from the other side): separate.
        let mut back = obs(0.0, 2.0, 5.0, 4);
        back.plane = back.plane.flipped();
        assert_eq!(m.merge(&mut map, &back), 3);
        assert_eq!(map.selected(2).count(), 1);
    }

    #[test]
    fn ordinary_and_ground_landmarks_follow_the_same_rules_and_never_mix_kinds() {
        let m = WeightedAverageMerger::default();
        let mut map = PlaneMap::new();
        let mut wall = obs(0.0, 2.0, 5.0, 0);
        wall.kind = PlaneKind::Ordinary;
        assert_eq!(m.merge(&mut map, &wall), 0);
        let mut again = obs(1.0, 3.0, 5.02, 1);
        again.kind = PlaneKind::Ordinary;
        assert_eq!(m.merge(&mut map, &again), 0);
        // The same plane seen as glass is another landmark.
        assert_eq!(m.merge(&mut map, &obs(0.0, 2.0, 5.0, 2)), 1);
        let mut ground = obs(0.0, 2.0, 5.0, 3);
        ground.kind = PlaneKind::Ground;
        assert_eq!(m.merge(&mut map, &ground), 2);
        // A decided association fuses even without hull overlap.
        let mut far = obs(10.0, 12.0, 5.0, 4);
        far.kind = PlaneKind::Ordinary;
        assert_eq!(m.fuse(&mut map, 0, &far), 0);
        assert_eq!(map.landmarks[0].observations, 3);
        assert_eq!(m.fuse(&mut map, 99, &far), 3);
        assert_eq!(map.landmarks[3].id, 3);
    }

    #[test]
    fn weights_are_capped() {
        let m = WeightedAverageMerger::default();
        let mut map = PlaneMap::new();
        for k in 0..30 {
            m.merge(&mut map, &obs(0.0, 2.0, 5.0, k));
        }
        m.merge(&mut map, &obs(0.0, 2.0, 5.099, 30));
        // Weight of the stored plane capped at 10: d moves by 0.099 / 11.
        assert!((map.landmarks[0].plane.d - (5.0 + 0.099 / 11.0)).abs() < 1e-9);
    }
}
