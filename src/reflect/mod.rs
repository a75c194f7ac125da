//! Reflective-plane detection in one scan.
//!
//! A [`ReflectiveDetector`] finds the glass and mirror planes of one frame:
//! it selects candidate points (dual-return discrepancies, intensity peaks),
//! fits up to a few planes to them with RANSAC, and bounds each plane by the
//! convex hull of its projected inliers. The paper's detector is
//! [`CandidateRansacDetector`] with dual-return candidates.

pub mod candidates;
pub mod detector;
pub mod intensity_peak;

pub use detector::{CandidateRansacDetector, CandidateSource, DetectorParams};
pub use intensity_peak::IntensityPeakParams;

use nalgebra::{Isometry3, Point3};

use crate::cloud::Frame;
use std::sync::Arc;

use crate::geometry::grid::{EvidenceGrid, Surface};
use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::sensor::OrganizedScan;

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
}

impl BoundedPlane {
    /// Bound `plane` by the hull of `points` projected into its chart.
    pub fn from_points(plane: Plane, points: impl IntoIterator<Item = Point3<f64>>) -> Self {
        let chart = PlaneChart::of(&plane);
        let projected: Vec<_> = points.into_iter().map(|p| chart.to_2d(&p)).collect();
        Self {
            plane,
            chart,
            boundary: ConvexPolygon::hull(&projected),
            evidence: None,
        }
    }

    /// Whether the plane point `q` lies within the reflective extent: where
    /// transparency evidence decides, its verdict; elsewhere the convex
    /// boundary grown by `margin`.
    #[inline]
    pub fn bounds(&self, q: &Point3<f64>, margin: f64) -> bool {
        let uv = self.chart.to_2d(q);
        match self.evidence.as_ref().map(|e| e.state(&uv)) {
            Some(Surface::Transparent) => return true,
            Some(Surface::Opaque) => return false,
            _ => {}
        }
        if margin == 0.0 {
            self.boundary.contains(&uv)
        } else {
            self.boundary.signed_distance(&uv) <= margin
        }
    }

    /// The same bounded plane in another frame (`t` maps the current frame to
    /// the new one); the boundary polygon is unchanged.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        Self {
            plane: self.plane.transformed(t),
            chart: self.chart.transformed(t),
            boundary: self.boundary.clone(),
            evidence: self.evidence.clone(),
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
