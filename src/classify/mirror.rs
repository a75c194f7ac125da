//! Mirror-back: reflections moved to where their objects really are.

use nalgebra::Point3;

use crate::geometry::Plane;

/// Mirror `points` (reflections seen behind `plane`) through the plane: the
/// Householder transform `x' = x - 2 (n·x + d) n`, which puts every virtual
/// point at its real object ("mapping around the corner").
pub fn mirror_back(plane: &Plane, points: &[Point3<f64>]) -> Vec<Point3<f64>> {
    points.iter().map(|p| plane.mirror(p)).collect()
}
