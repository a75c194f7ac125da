//! Merging duplicate landmarks after a loop closure.
//!
//! Before a loop is closed the estimate has drifted, and a plane seen again
//! on the revisit may fail association and become a second landmark. Once
//! the loop is closed both copies lie on one plane. Two landmarks are the
//! same plane when they are of the same kind (a reflective plane never
//! merges with a wall, so no virtual plane behind a mirror joins the
//! room), their normals agree within `merge_max_angle_deg` (opposite faces
//! of a wall face opposite ways and stay apart), each one's boundary
//! centre lies within `merge_max_offset` of the other's plane, and their
//! extents overlap by `merge_min_overlap` of the smaller one (coplanar
//! panes side by side stay apart). The older landmark (lower id) keeps its
//! id; the newer one's observations are re-keyed to it in the log
//! (ORB-SLAM's "keep the older", reference section 2.5), and the plane is
//! the observation-weighted mean of the two.

use nalgebra::Point3;

use super::LoopClosureParams;
use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::map::landmark::hull_on_plane;
use crate::map::{Landmark, PlaneMap};
use crate::slam::log::TrackingLog;

/// What [`merge_duplicates`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MergeDuplicates {
    /// `(kept id, removed id)` per merge, in the order they were made.
    pub merged: Vec<(usize, usize)>,
}

/// The centre of a boundary (the vertices' mean).
fn centre(boundary: &[Point3<f64>]) -> Option<Point3<f64>> {
    if boundary.is_empty() {
        return None;
    }
    let sum = boundary
        .iter()
        .fold(nalgebra::Vector3::zeros(), |s, p| s + p.coords);
    Some(Point3::from(sum / boundary.len() as f64))
}

/// Whether landmarks `a` and `b` are one plane by `params`.
pub fn are_duplicates(a: &Landmark, b: &Landmark, params: &LoopClosureParams) -> bool {
    if a.kind != b.kind {
        return false;
    }
    if a.plane.normal_cosine(&b.plane) < params.merge_max_angle_deg.to_radians().cos() {
        return false;
    }
    let (Some(ca), Some(cb)) = (centre(&a.boundary), centre(&b.boundary)) else {
        return false;
    };
    if a.plane.signed_distance(&cb).abs() > params.merge_max_offset
        || b.plane.signed_distance(&ca).abs() > params.merge_max_offset
    {
        return false;
    }
    let chart = PlaneChart::of(&a.plane);
    let polygon = |pts: &[Point3<f64>]| {
        ConvexPolygon::hull(&pts.iter().map(|p| chart.to_2d(p)).collect::<Vec<_>>())
    };
    let (pa, pb) = (polygon(&a.boundary), polygon(&b.boundary));
    let smaller = pa.area().min(pb.area());
    smaller > 0.0 && pa.intersection_area(&pb) >= params.merge_min_overlap * smaller
}

/// Fold landmark `b` into `a` (weights: their observation counts).
fn fold(a: &mut Landmark, b: &Landmark) {
    let (wa, wb) = (a.observations as f64, b.observations as f64);
    let n = a.plane.normal * wa + b.plane.normal * wb;
    let d = a.plane.d * wa + b.plane.d * wb;
    if let Some(p) = Plane::new(n / (wa + wb), d / (wa + wb)) {
        a.plane = p;
    }
    let hull = hull_on_plane(&a.plane, a.boundary.iter().chain(&b.boundary).copied());
    if hull.len() >= 3 {
        a.boundary = hull;
    }
    a.observations += b.observations;
    a.first_frame = a.first_frame.min(b.first_frame);
    a.last_frame = a.last_frame.max(b.last_frame);
}

/// Merge every pair of duplicate landmarks of `map` ([module docs](self)),
/// re-keying the log's observations of the removed ones. Deterministic:
/// landmarks are visited in map order, each newer one into the first older
/// one it duplicates.
pub fn merge_duplicates(
    map: &mut PlaneMap,
    log: &mut TrackingLog,
    params: &LoopClosureParams,
) -> MergeDuplicates {
    let mut out = MergeDuplicates::default();
    let mut j = 1;
    while j < map.landmarks.len() {
        let target = (0..j).find(|&i| are_duplicates(&map.landmarks[i], &map.landmarks[j], params));
        match target {
            Some(i) => {
                let b = map.landmarks.remove(j);
                fold(&mut map.landmarks[i], &b);
                out.merged.push((map.landmarks[i].id, b.id));
            }
            None => j += 1,
        }
    }
    if !out.merged.is_empty() {
        let mut to: std::collections::BTreeMap<usize, usize> =
            out.merged.iter().map(|&(a, b)| (b, a)).collect();
        // A landmark merged into one that was itself merged later.
        let keys: Vec<usize> = to.keys().copied().collect();
        for k in keys {
            let mut t = to[&k];
            while let Some(&next) = to.get(&t) {
                t = next;
            }
            to.insert(k, t);
        }
        for o in &mut log.observations {
            if let Some(&t) = to.get(&o.landmark) {
                o.landmark = t;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::PlaneKind;
    use crate::map::PlaneObservation;
    use crate::slam::log::LandmarkObservation;
    use nalgebra::{Matrix3, Vector3};

    /// A wall landmark on `x = x0` facing `-x` (seen from the origin side),
    /// spanning `y0..y1`, `z` 0..3.
    fn wall(id: usize, kind: PlaneKind, x0: f64, y0: f64, y1: f64, flip: bool) -> Landmark {
        let plane = if flip {
            Plane::new(Vector3::x(), -x0).unwrap()
        } else {
            Plane::new(-Vector3::x(), x0).unwrap()
        };
        let obs = PlaneObservation {
            kind,
            plane,
            boundary: vec![
                Point3::new(x0, y0, 0.0),
                Point3::new(x0, y1, 0.0),
                Point3::new(x0, y1, 3.0),
                Point3::new(x0, y0, 3.0),
            ],
            frame: id,
        };
        let mut l = Landmark::new(id, &obs);
        l.observations = 4;
        l
    }

    fn observation(frame: usize, landmark: usize) -> LandmarkObservation {
        LandmarkObservation {
            frame,
            landmark,
            kind: PlaneKind::Ordinary,
            plane: Plane::new(Vector3::x(), 1.0).unwrap(),
            count: 10,
            centroid: Point3::origin(),
            scatter: Matrix3::zeros(),
        }
    }

    /// The same wall mapped twice (2 cm apart, overlapping) becomes one
    /// landmark and its observations follow; a coplanar pane beside it, the
    /// wall's other face, and a reflective plane on it stay apart.
    #[test]
    fn only_true_duplicates_merge_and_observations_follow() {
        let params = LoopClosureParams::default();
        let mut map = PlaneMap::new();
        map.landmarks
            .push(wall(0, PlaneKind::Ordinary, 5.0, 0.0, 4.0, false));
        map.landmarks
            .push(wall(1, PlaneKind::Ordinary, 5.0, 4.5, 8.0, false));
        map.landmarks
            .push(wall(2, PlaneKind::Ordinary, 5.0, 0.0, 4.0, true));
        map.landmarks
            .push(wall(3, PlaneKind::Reflective, 5.0, 0.0, 4.0, false));
        map.landmarks
            .push(wall(4, PlaneKind::Ordinary, 5.02, 1.0, 3.5, false));
        let mut log = TrackingLog {
            frames: Vec::new(),
            observations: vec![observation(0, 0), observation(1, 4), observation(2, 1)],
            loops: Vec::new(),
        };
        let out = merge_duplicates(&mut map, &mut log, &params);
        assert_eq!(out.merged, vec![(0, 4)]);
        assert_eq!(
            map.landmarks.iter().map(|l| l.id).collect::<Vec<_>>(),
            vec![0, 1, 2, 3]
        );
        assert_eq!(map.landmarks[0].observations, 8);
        assert!((map.landmarks[0].plane.d - 5.01).abs() < 1e-9);
        assert_eq!(
            log.observations
                .iter()
                .map(|o| o.landmark)
                .collect::<Vec<_>>(),
            vec![0, 0, 1]
        );
        // Off when the offsets differ beyond the threshold.
        let strict = LoopClosureParams {
            merge_max_offset: 0.01,
            ..params
        };
        let mut map = PlaneMap::new();
        map.landmarks
            .push(wall(0, PlaneKind::Ordinary, 5.0, 0.0, 4.0, false));
        map.landmarks
            .push(wall(4, PlaneKind::Ordinary, 5.02, 1.0, 3.5, false));
        assert!(merge_duplicates(&mut map, &mut log, &strict)
            .merged
            .is_empty());
    }
}
