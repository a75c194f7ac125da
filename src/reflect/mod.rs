//! Reflective-plane detection in one scan.
//!
//! A [`ReflectiveDetector`] finds the glass and mirror planes of one frame:
//! it selects candidate points (dual-return discrepancies, intensity peaks),
//! fits up to a few planes to them with RANSAC, and bounds each plane by the
//! convex hull of its projected inliers. The paper's detector is
//! [`CandidateRansacDetector`] with dual-return candidates.

pub mod candidates;
pub mod detector;
pub mod echo_split;
pub mod intensity_peak;

pub use detector::{CandidateRansacDetector, CandidateSource, DetectorParams};
pub use echo_split::{EchoHistogram, EchoSplit, EchoSplitParams};
pub use intensity_peak::IntensityPeakParams;

use nalgebra::{Isometry3, Point2, Point3};

use crate::cloud::Frame;
use std::sync::Arc;

use crate::geometry::grid::{EvidenceGrid, Surface};
use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::sensor::OrganizedScan;

/// Whether a landmark with this probability of being a mirror is more
/// likely a mirror than glass: then nothing behind it is real, and its
/// strong echoes are bright images, not transmissions.
pub fn more_likely_mirror(mirror_probability: f64) -> bool {
    mirror_probability > 0.5
}

/// A plane with a convex boundary in its chart, in some frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundedPlane {
    /// The plane (oriented towards its observer: `d > 0` in the sensor frame).
    pub plane: Plane,
    /// The 2-D chart the boundary is expressed in.
    pub chart: PlaneChart,
    /// Convex boundary in chart coordinates.
    pub boundary: ConvexPolygon,
    /// Transparency evidence in the same chart, when gathered: where it is
    /// decided it overrides the convex boundary.
    pub evidence: Option<Arc<EvidenceGrid>>,
    /// Separate reflective panes on this plane (chart coordinates), when
    /// fitted: then the reflective extent is exactly their union (possibly
    /// empty), and `boundary` and `evidence` are not consulted.
    pub panes: Option<Arc<Vec<ConvexPolygon>>>,
    /// How the echoes behind this plane split into reflected and
    /// transmitted ones by strength, when learned.
    pub echo_split: Option<EchoSplit>,
    /// The probability that the plane is a mirror (nothing behind it is
    /// real) rather than glass, from all of its evidence over the sequence
    /// ([`glass_or_mirror`](mod@crate::map::glass_or_mirror)), when estimated.
    pub mirror_probability: Option<f64>,
    /// The heights (world z, m) of the floors and ceilings seen directly
    /// that run on behind the plane: transmissions confirmed by the space
    /// seen directly end at them ([`crate::classify::levels`]).
    pub levels_behind: Vec<f64>,
    /// The share of reflections among the echoes behind the plane, where
    /// their strengths tell it
    /// ([`reflection_share`](mod@crate::map::reflection_share)): the prior
    /// of every point behind it.
    pub reflection_share: Option<f64>,
    /// The share of reflections among the echoes behind the plane that
    /// the space seen directly decides
    /// ([`glass_or_mirror`](mod@crate::map::glass_or_mirror)): the prior of
    /// a point behind it that no test weighs.
    pub decided_share: Option<f64>,
}

impl BoundedPlane {
    /// Whether the plane is more likely a mirror than glass.
    pub fn is_mirror(&self) -> bool {
        self.mirror_probability.is_some_and(more_likely_mirror)
    }

    /// Bound `plane` by the hull of `points` projected into its chart.
    pub fn from_points(plane: Plane, points: impl IntoIterator<Item = Point3<f64>>) -> Self {
        let chart = PlaneChart::of(&plane);
        let projected: Vec<_> = points.into_iter().map(|p| chart.to_2d(&p)).collect();
        Self {
            plane,
            chart,
            boundary: ConvexPolygon::hull(&projected),
            evidence: None,
            panes: None,
            echo_split: None,
            mirror_probability: None,
            levels_behind: Vec::new(),
            reflection_share: None,
            decided_share: None,
        }
    }

    /// Whether the plane point `q` lies within the reflective extent: with
    /// panes, inside one of them (grown by `margin`) and not on a cell the
    /// evidence calls opaque; otherwise, where
    /// transparency evidence decides, its verdict, and elsewhere the convex
    /// boundary grown by `margin`.
    #[inline]
    pub fn bounds(&self, q: &Point3<f64>, margin: f64) -> bool {
        self.bounds_2d(&self.chart.to_2d(q), margin)
    }

    /// [`BoundedPlane::bounds`] for a point given in chart coordinates.
    pub fn bounds_2d(&self, uv: &Point2<f64>, margin: f64) -> bool {
        let uv = *uv;
        if let Some(panes) = &self.panes {
            // Opaque evidence inside a convex pane is a mullion or wall strip.
            if let Some(Surface::Opaque | Surface::Open) =
                self.evidence.as_ref().map(|e| e.state(&uv))
            {
                return false;
            }
            return panes.iter().any(|p| {
                if margin == 0.0 {
                    p.contains(&uv)
                } else {
                    p.within(&uv, margin)
                }
            });
        }
        match self.evidence.as_ref().map(|e| e.state(&uv)) {
            Some(Surface::Transparent) => return true,
            Some(Surface::Opaque | Surface::Open) => return false,
            _ => {}
        }
        if margin == 0.0 {
            self.boundary.contains(&uv)
        } else {
            self.boundary.within(&uv, margin)
        }
    }

    /// Whether the plane point `uv` (chart coordinates) lies just beyond the
    /// reflective extent, within `reach` of it, where the evidence allows
    /// unseen glass ([`EvidenceGrid::could_hide_glass`]): glass may well
    /// continue there.
    /// Glass echoes only near normal incidence, so a pane's top above the
    /// sensor or its far edge seen obliquely gives no echo; the extent stops
    /// at the last echo, the glass does not.
    pub fn beyond_seen_extent_2d(&self, uv: &Point2<f64>, reach: f64) -> bool {
        if !(reach > 0.0) {
            return false;
        }
        if self
            .evidence
            .as_ref()
            .is_some_and(|e| !e.could_hide_glass(uv))
        {
            return false;
        }
        if self.bounds_2d(uv, 0.0) {
            return false;
        }
        let distance = match &self.panes {
            Some(panes) => panes
                .iter()
                .map(|p| p.signed_distance(uv))
                .fold(f64::INFINITY, f64::min),
            None => self.boundary.signed_distance(uv),
        };
        distance <= reach
    }

    /// A box in chart coordinates, `(min, max)`, outside which
    /// [`BoundedPlane::bounds`] with this `margin` is false: a cheap test
    /// that spares most beams the boundary and evidence lookups.
    pub fn extent_2d(&self, margin: f64) -> (Point2<f64>, Point2<f64>) {
        let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut cover = |p: &Point2<f64>, grow: f64| {
            lo = Point2::new(lo.x.min(p.x - grow), lo.y.min(p.y - grow));
            hi = Point2::new(hi.x.max(p.x + grow), hi.y.max(p.y + grow));
        };
        // Growing by `margin` covers both "inside" and "within the margin".
        let grow = margin.max(0.0);
        match &self.panes {
            // With panes only they can say yes.
            Some(panes) => panes
                .iter()
                .flat_map(|p| p.vertices())
                .for_each(|v| cover(v, grow)),
            None => {
                self.boundary.vertices().iter().for_each(|v| cover(v, grow));
                // Decided transparent evidence may reach beyond the hull.
                if let Some(e) = &self.evidence {
                    let size = nalgebra::Vector2::new(e.cols as f64, e.rows as f64) * e.cell;
                    cover(&e.min, 0.0);
                    cover(&(e.min + size), 0.0);
                }
            }
        }
        (lo, hi)
    }

    /// The same bounded plane in another frame (`t` maps the current frame to
    /// the new one); the boundary polygon is unchanged.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        Self {
            plane: self.plane.transformed(t),
            chart: self.chart.transformed(t),
            boundary: self.boundary.clone(),
            evidence: self.evidence.clone(),
            panes: self.panes.clone(),
            echo_split: self.echo_split,
            mirror_probability: self.mirror_probability,
            levels_behind: self.levels_behind.clone(),
            reflection_share: self.reflection_share,
            decided_share: self.decided_share,
        }
    }

    /// This bounded plane with its normal facing `viewpoint` (the chart and
    /// boundary are unchanged: they do not depend on the orientation).
    pub fn facing(&self, viewpoint: &Point3<f64>) -> Self {
        Self {
            plane: self.plane.facing(viewpoint),
            ..self.clone()
        }
    }

    /// Boundary vertices in 3-D.
    pub fn boundary_3d(&self) -> Vec<Point3<f64>> {
        self.boundary
            .vertices()
            .iter()
            .map(|q| self.chart.to_3d(q))
            .collect()
    }
}

/// World-frame bounded planes as seen from a sensor with pose `pose`
/// (`T_world_sensor`): in the sensor frame, each facing the sensor.
pub fn planes_seen_from(planes: &[BoundedPlane], pose: &Isometry3<f64>) -> Vec<BoundedPlane> {
    let to_sensor = pose.inverse();
    let origin = Point3::origin();
    planes
        .iter()
        .map(|bp| bp.transformed(&to_sensor).facing(&origin))
        .collect()
}

/// One reflective plane found in a scan (sensor frame).
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectivePlane {
    /// Plane and hull boundary, sensor frame, `d > 0`.
    pub bounded: BoundedPlane,
    /// Indices (into the frame's points) of the RANSAC inliers.
    pub inliers: Vec<u32>,
}

/// The result of detection in one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Detection {
    /// Indices of the candidate points (possibly on a reflective surface).
    pub candidates: Vec<u32>,
    /// Planes found, largest first.
    pub planes: Vec<ReflectivePlane>,
}

/// Finds reflective planes in one scan. Implementations are selected by name
/// in the configuration (`[detector] name = ...`).
pub trait ReflectiveDetector: Send + Sync {
    /// The name this detector is selected by.
    fn name(&self) -> &'static str;

    /// Candidates and planes of one frame (sensor frame). `seed` makes the
    /// randomised parts deterministic.
    fn detect(&self, frame: &Frame, scan: &OrganizedScan, seed: u64) -> Detection;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::grid::EvidenceGrid;
    use nalgebra::{Point2, Vector3};

    /// The unit square on the plane x = 2 (normal facing the origin).
    fn square() -> BoundedPlane {
        let plane = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 2.0).unwrap();
        let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        BoundedPlane::from_points(plane, corners.iter().map(|&(y, z)| Point3::new(2.0, y, z)))
    }

    #[test]
    fn hull_edges_are_inclusive_and_margins_grow_them() {
        let b = square();
        assert!((b.boundary.area() - 1.0).abs() < 1e-9);
        assert!(b.bounds(&Point3::new(2.0, 0.5, 0.999), 0.0));
        assert!(b.bounds(&Point3::new(2.0, 1.0, 0.5), 0.0), "on the edge");
        assert!(!b.bounds(&Point3::new(2.0, 1.01, 0.5), 0.0));
        assert!(b.bounds(&Point3::new(2.0, 1.04, 0.5), 0.05));
        assert!(!b.bounds(&Point3::new(2.0, 1.06, 0.5), 0.05));
        assert!(
            !b.bounds(&Point3::new(2.0, -0.01, -0.01), 0.0),
            "outside a corner"
        );
    }

    #[test]
    fn decided_evidence_overrides_the_hull() {
        let mut b = square();
        let uv = |y: f64, z: f64| b.chart.to_2d(&Point3::new(2.0, y, z));
        let (inside, outside) = (uv(0.5, 0.5), uv(1.5, 0.5));
        let lo = Point2::new(inside.x.min(outside.x) - 1.0, inside.y.min(outside.y) - 1.0);
        let hi = Point2::new(inside.x.max(outside.x) + 1.0, inside.y.max(outside.y) + 1.0);
        let mut grid = EvidenceGrid::new(lo, hi, 0.1, 2, 10_000).unwrap();
        grid.vote(&inside, 0, 5);
        grid.vote(&outside, 5, 0);
        grid.finalize();
        b.evidence = Some(Arc::new(grid));
        assert!(
            !b.bounds(&Point3::new(2.0, 0.5, 0.5), 0.0),
            "opaque inside the hull"
        );
        assert!(
            b.bounds(&Point3::new(2.0, 1.5, 0.5), 0.0),
            "transparent outside the hull"
        );
        assert!(
            b.bounds(&Point3::new(2.0, 0.2, 0.8), 0.0),
            "undecided: the hull"
        );
    }

    /// `extent_2d` never excludes a point that `bounds` accepts: with the
    /// hull alone, with transparent evidence beyond the hull, and with
    /// panes, for margins 0 and 0.2, over a grid of plane points.
    #[test]
    fn the_chart_extent_holds_every_bounded_point() {
        let mut with_evidence = square();
        let uv = |y: f64, z: f64| with_evidence.chart.to_2d(&Point3::new(2.0, y, z));
        let (a, b) = (uv(-2.0, -2.0), uv(3.0, 3.0));
        let lo = Point2::new(a.x.min(b.x), a.y.min(b.y));
        let hi = Point2::new(a.x.max(b.x), a.y.max(b.y));
        let mut grid = EvidenceGrid::new(lo, hi, 0.1, 1, 100_000).unwrap();
        grid.vote(&uv(2.5, 0.5), 5, 0);
        grid.finalize();
        with_evidence.evidence = Some(Arc::new(grid));
        let mut with_panes = square();
        let pane = |y0: f64, y1: f64| {
            let (p, q) = (with_panes.chart.to_2d(&Point3::new(2.0, y0, 0.0)), {
                with_panes.chart.to_2d(&Point3::new(2.0, y1, 0.4))
            });
            crate::geometry::ConvexPolygon::rectangle(
                Point2::new(p.x.min(q.x), p.y.min(q.y)),
                Point2::new(p.x.max(q.x), p.y.max(q.y)),
            )
        };
        with_panes.panes = Some(Arc::new(vec![pane(-1.0, -0.5), pane(1.5, 2.5)]));
        for bp in [square(), with_evidence, with_panes] {
            for margin in [0.0, 0.2] {
                let (lo, hi) = bp.extent_2d(margin);
                let mut accepted = 0;
                for i in -40..=40 {
                    for j in -40..=40 {
                        let q = Point3::new(2.0, i as f64 * 0.1, j as f64 * 0.1);
                        if bp.bounds(&q, margin) {
                            accepted += 1;
                            let uv = bp.chart.to_2d(&q);
                            assert!(
                                uv.x >= lo.x && uv.x <= hi.x && uv.y >= lo.y && uv.y <= hi.y,
                                "{q} is bounded but outside the extent"
                            );
                        }
                    }
                }
                assert!(accepted > 0);
            }
        }
    }
}
