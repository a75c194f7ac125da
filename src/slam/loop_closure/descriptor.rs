//! A place descriptor of a frame's plane constellation.
//!
//! Plane SLAM already has the frame's planes, so a descriptor of their
//! constellation costs almost nothing (PbMap, LiPMatch; see
//! `shared/reference/loop-closure-and-degeneracy.md`, section 1.5). It must
//! not depend on the heading (a revisit may come from the other way) nor on
//! the world frame, so it keeps only what the sensor frame's yaw leaves
//! unchanged:
//!
//! - per plane: its kind, whether it is horizontal (floor, ceiling, sills)
//!   or vertical, its distance from the sensor (`d`, in `bin` steps), and
//!   its extent (`√area` as the weight: a large wall counts more than a
//!   sill, but not quadratically more);
//! - per pair of vertical planes: the angle between their normals (a
//!   corridor gives 0° and 180° only, a room corner 90°), weighted by the
//!   smaller extent of the two.
//!
//! The two histograms are compared by cosine similarity; the distance is
//! `1 − similarity` in `[0, 1]`. The descriptor only ranks candidates: in a
//! corridor of repeated panes every place looks alike, and the geometric
//! verification ([`super::verify`]) decides.

use crate::frontend::FramePlane;
use crate::io::PlaneKind;

/// Distance bins (of `RANGE_BIN` metres) of the per-plane histogram.
const RANGE_BINS: usize = 24;
/// Width of a distance bin, m.
const RANGE_BIN: f64 = 0.5;
/// Angle bins (over 0-180°) of the pair histogram.
const ANGLE_BINS: usize = 12;
/// A plane whose normal has a vertical component beyond this is horizontal.
const HORIZONTAL_NZ: f64 = 0.7;

/// A frame's plane-constellation descriptor ([`module docs`](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneDescriptor {
    /// Per (kind, horizontal) class and distance bin: the summed `√area`.
    planes: Vec<f64>,
    /// Per normal-angle bin of vertical plane pairs: the summed weight.
    pairs: Vec<f64>,
}

/// Index of a plane's class: kind × horizontal/vertical.
fn class(kind: PlaneKind, horizontal: bool) -> usize {
    let k = match kind {
        PlaneKind::Ground => 0,
        PlaneKind::Ordinary => 1,
        PlaneKind::Reflective => 2,
    };
    2 * k + usize::from(horizontal)
}

/// The weight of one distance value spread linearly over its two nearest
/// bins (so a plane 1 cm across a bin edge does not change the
/// descriptor much).
fn spread(hist: &mut [f64], offset: usize, bins: usize, x: f64, w: f64) {
    if !(x.is_finite() && w.is_finite()) {
        return;
    }
    let x = x.clamp(0.0, (bins - 1) as f64);
    let lo = x.floor() as usize;
    let frac = x - lo as f64;
    hist[offset + lo] += w * (1.0 - frac);
    if lo + 1 < bins {
        hist[offset + lo + 1] += w * frac;
    }
}

impl PlaneDescriptor {
    /// The descriptor of a frame's planes (sensor frame, the sensor's up
    /// axis `z`).
    pub fn of(planes: &[FramePlane]) -> Self {
        let mut hist = vec![0.0; 6 * RANGE_BINS];
        let mut pairs = vec![0.0; ANGLE_BINS];
        let mut vertical = Vec::new();
        for p in planes {
            let horizontal = p.plane.normal.z.abs() > HORIZONTAL_NZ;
            let w = p.area.max(0.0).sqrt();
            let offset = class(p.kind, horizontal) * RANGE_BINS;
            spread(&mut hist, offset, RANGE_BINS, p.plane.d / RANGE_BIN, w);
            if !horizontal {
                vertical.push((p.plane.normal, w));
            }
        }
        let step = 180.0 / ANGLE_BINS as f64;
        for (i, (a, wa)) in vertical.iter().enumerate() {
            for (b, wb) in &vertical[i + 1..] {
                // Horizontal components only: a yaw-invariant angle.
                let (ha, hb) = (a.xy(), b.xy());
                let norm = ha.norm() * hb.norm();
                if !(norm > 0.0) {
                    continue;
                }
                let angle = (ha.dot(&hb) / norm).clamp(-1.0, 1.0).acos().to_degrees();
                spread(&mut pairs, 0, ANGLE_BINS, angle / step, wa.min(*wb));
            }
        }
        Self {
            planes: hist,
            pairs,
        }
    }

    /// `1 −` the cosine similarity of two descriptors (both histograms
    /// concatenated), in `[0, 1]`; 1 when either is empty.
    pub fn distance(&self, other: &Self) -> f64 {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let ab = dot(&self.planes, &other.planes) + dot(&self.pairs, &other.pairs);
        let aa = dot(&self.planes, &self.planes) + dot(&self.pairs, &self.pairs);
        let bb = dot(&other.planes, &other.planes) + dot(&other.pairs, &other.pairs);
        let norm = (aa * bb).sqrt();
        if !(norm > 0.0) {
            return 1.0;
        }
        (1.0 - ab / norm).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;
    use nalgebra::{Isometry3, Point3, Vector3};

    /// A frame plane of `kind` on `plane` with a square hull of `side`.
    fn plane(kind: PlaneKind, n: Vector3<f64>, d: f64, side: f64) -> FramePlane {
        let plane = Plane::new(n.normalize(), d).unwrap();
        let chart = crate::geometry::PlaneChart::of(&plane);
        let h = side / 2.0;
        let hull = crate::geometry::ConvexPolygon::rectangle(
            nalgebra::Point2::new(-h, -h),
            nalgebra::Point2::new(h, h),
        );
        FramePlane {
            kind,
            plane,
            chart,
            area: hull.area(),
            hull,
            centroid: plane.project(&Point3::origin()),
            inliers: Vec::new(),
            scatter: nalgebra::Matrix3::zeros(),
        }
    }

    /// A room corner: floor, two walls at right angles, a glass pane.
    fn room() -> Vec<FramePlane> {
        vec![
            plane(PlaneKind::Ground, Vector3::z(), 1.5, 6.0),
            plane(PlaneKind::Ordinary, Vector3::x(), 2.0, 3.0),
            plane(PlaneKind::Ordinary, Vector3::y(), 3.0, 3.0),
            plane(PlaneKind::Reflective, -Vector3::y(), 1.2, 2.0),
        ]
    }

    /// The same planes seen from a sensor turned by any yaw give the same
    /// descriptor; another layout (a corridor: two parallel walls, no
    /// corner) is far from it.
    #[test]
    fn the_descriptor_ignores_the_heading_and_tells_layouts_apart() {
        let a = PlaneDescriptor::of(&room());
        let yaw = Isometry3::rotation(Vector3::z() * 2.1);
        let turned: Vec<FramePlane> = room().iter().map(|p| p.transformed(&yaw)).collect();
        let b = PlaneDescriptor::of(&turned);
        assert!(a.distance(&b) < 1e-9, "{}", a.distance(&b));
        let corridor = vec![
            plane(PlaneKind::Ground, Vector3::z(), 1.5, 6.0),
            plane(PlaneKind::Ordinary, Vector3::y(), 1.2, 3.0),
            plane(PlaneKind::Ordinary, -Vector3::y(), 1.2, 3.0),
            plane(PlaneKind::Ordinary, -Vector3::z(), 1.5, 6.0),
        ];
        let c = PlaneDescriptor::of(&corridor);
        assert!(a.distance(&c) > 0.3, "{}", a.distance(&c));
        assert_eq!(PlaneDescriptor::of(&[]).distance(&a), 1.0);
    }

    /// A small move gives a small distance.
    #[test]
    fn a_small_move_changes_the_descriptor_little() {
        let near = room();
        let moved: Vec<FramePlane> = near
            .iter()
            .map(|p| p.transformed(&Isometry3::translation(0.05, 0.03, 0.0)))
            .collect();
        let d = PlaneDescriptor::of(&near).distance(&PlaneDescriptor::of(&moved));
        assert!(d < 0.05, "{d}");
    }
}
