//! Scan-to-map association: which landmark each frame plane observes.
//!
//! The paper's map matching: with the frame's (predicted) pose the planes
//! are in the world frame, so instead of the area ratio the hulls' overlap
//! is tested — the frame hull is projected onto the landmark's plane and
//! the overlap area must be at least `min_overlap` (paper: 0.7) of the
//! smaller hull. Normal and offset gates (as in frame matching) come first;
//! kinds must agree. Each frame plane is associated with the landmark of
//! largest overlap ratio.
//!
//! The offset gate is the distance of the frame plane's centroid from the
//! landmark plane, not the difference of the offsets `d`: in the world
//! frame `d` is measured at the world origin, so two estimates of one
//! plane whose normals differ by a degree differ in `d` by 0.17 m per 10 m
//! between the plane and the origin — the gate would depend on where the
//! world frame happens to be. (Frame-to-frame matching compares `d` in the
//! sensor frames, where the origin is the sensor, as the paper does.)

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::frontend::FramePlane;
use crate::geometry::{ConvexPolygon, PlaneChart};
use crate::io::PlaneKind;
use crate::map::PlaneMap;
use crate::registration::Correspondence;

/// Scan-to-map matching thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapMatchParams {
    /// World-frame normals must have a larger cosine.
    pub min_normal_cos: f64,
    /// The frame plane's centroid must be closer than this to the landmark
    /// plane, m.
    pub max_offset: f64,
    /// Overlap area over the smaller hull's area must reach this (paper:
    /// 0.7).
    pub min_overlap: f64,
}

impl Default for MapMatchParams {
    /// [`MAP_MATCHING`](crate::slam::tracker::MAP_MATCHING).
    fn default() -> Self {
        crate::slam::tracker::MAP_MATCHING
    }
}

/// Overlap of two convex polygons as a share of the smaller one's area
/// (0 when either is empty).
pub fn overlap_ratio(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    let smaller = a.area().min(b.area());
    if !(smaller > 0.0) {
        return 0.0;
    }
    a.intersection_area(b) / smaller
}

/// Pairs (frame plane in the sensor frame, landmark plane in the world)
/// for every frame plane that matches a landmark at pose `pose`
/// (`T_world_sensor`). `target_index` is the landmark's index in
/// `map.landmarks`.
pub fn associate(
    planes: &[FramePlane],
    pose: &Isometry3<f64>,
    map: &PlaneMap,
    params: &MapMatchParams,
) -> Vec<Correspondence> {
    // Landmark charts and hulls, built on first use.
    let mut hulls: Vec<Option<(PlaneChart, ConvexPolygon)>> = vec![None; map.landmarks.len()];
    let mut out = Vec::new();
    for (i, fp) in planes.iter().enumerate() {
        let world = fp.plane.transformed(pose);
        let centroid = pose * fp.centroid;
        let corners: Vec<_> = fp.hull_3d().iter().map(|p| pose * p).collect();
        let mut best: Option<(f64, usize)> = None;
        for (j, l) in map.landmarks.iter().enumerate() {
            if l.kind != fp.kind
                || !(world.normal_cosine(&l.plane) > params.min_normal_cos)
                || !(l.plane.signed_distance(&centroid).abs() < params.max_offset)
            {
                continue;
            }
            let (chart, hull) = hulls[j].get_or_insert_with(|| {
                let chart = PlaneChart::of(&l.plane);
                let uv: Vec<_> = l.boundary.iter().map(|p| chart.to_2d(p)).collect();
                (chart, ConvexPolygon::hull(&uv))
            });
            let projected: Vec<_> = corners.iter().map(|p| chart.to_2d(p)).collect();
            let ratio = overlap_ratio(&ConvexPolygon::hull(&projected), hull);
            if ratio >= params.min_overlap && best.is_none_or(|(r, _)| ratio > r) {
                best = Some((ratio, j));
            }
        }
        if let Some((_, j)) = best {
            out.push(Correspondence {
                source: fp.plane,
                target: map.landmarks[j].plane,
                ground: fp.kind == PlaneKind::Ground,
                source_index: i,
                target_index: j,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    #[test]
    fn overlap_is_relative_to_the_smaller_hull() {
        let big = ConvexPolygon::rectangle(Point2::new(0.0, 0.0), Point2::new(10.0, 2.0));
        let inside = ConvexPolygon::rectangle(Point2::new(1.0, 0.5), Point2::new(2.0, 1.5));
        let half = ConvexPolygon::rectangle(Point2::new(9.0, 0.0), Point2::new(11.0, 2.0));
        assert!((overlap_ratio(&big, &inside) - 1.0).abs() < 1e-12);
        assert!((overlap_ratio(&half, &big) - 0.5).abs() < 1e-12);
        assert_eq!(overlap_ratio(&big, &ConvexPolygon::default()), 0.0);
    }
}
