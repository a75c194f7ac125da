//! The mirror-image support test's seam and its two guards: a surface
//! seen near a mirror image is evidence of a reflection, except the
//! point's own surface and a surface perpendicular to the mirror plane,
//! which support the image whatever the point is.

use nalgebra::{Point3, Vector3};

use super::DecisionParams;
use crate::geometry::Plane;

/// Whether the mirror image `mirrored` of point `p` lies so near the point
/// that the point's own surface would support it
/// ([`DecisionParams::support_excludes_own_surface`]).
pub(super) fn supports_itself(
    params: &DecisionParams,
    p: &Point3<f64>,
    mirrored: &Point3<f64>,
) -> bool {
    params.support_excludes_own_surface && (mirrored - p).norm() <= params.support_radius
}

/// Answers "is there an observed surface near this point" (sensor frame),
/// e.g. a k-d tree of Normal points.
pub trait SurfaceSupport {
    /// Whether an observed surface point lies within `radius` of `p`.
    fn near(&self, p: &Point3<f64>, radius: f64) -> bool;

    /// The unit normal of the observed surface at the point nearest to `p`
    /// within `radius`, where the points there make a plane; `None` where
    /// they do not, or where the support keeps no such shape.
    fn normal_near(&self, _p: &Point3<f64>, _radius: f64) -> Option<Vector3<f64>> {
        None
    }
}

/// Whether the surface supporting the mirror image `mirrored` is within
/// `max_deg` degrees of perpendicular to `plane`
/// ([`DecisionParams::perpendicular_support_deg`]).
pub(super) fn support_is_perpendicular(
    support: Option<&dyn SurfaceSupport>,
    plane: &Plane,
    mirrored: &Point3<f64>,
    radius: f64,
    max_deg: f64,
) -> bool {
    max_deg > 0.0
        && support
            .and_then(|s| s.normal_near(mirrored, radius))
            .is_some_and(|n| n.dot(&plane.normal).abs() < max_deg.to_radians().sin())
}
