//! Mirror-back: reflections moved to where their objects really are.

use nalgebra::Point3;

use super::boundary::BeamPlanes;
use super::Class;
use crate::cloud::Frame;
use crate::geometry::Plane;
use crate::reflect::BoundedPlane;

/// Mirror `points` (reflections seen behind `plane`) through the plane: the
/// Householder transform `x' = x - 2 (n·x + d) n`, which puts every virtual
/// point at its real object ("mapping around the corner").
pub fn mirror_back(plane: &Plane, points: &[Point3<f64>]) -> Vec<Point3<f64>> {
    points.iter().map(|p| plane.mirror(p)).collect()
}

/// The true positions (sensor frame) of a frame's Reflection points: each is
/// mirrored through the first plane its beam crosses. Returns
/// `(point index, mirrored position)`; a reflection whose beam crosses no
/// plane (possible only with other classifiers) is skipped.
pub fn mirror_reflections(
    frame: &Frame,
    classes: &[Class],
    planes: &[BoundedPlane],
    hull_margin: f64,
) -> Vec<(usize, Point3<f64>)> {
    let beams = BeamPlanes::hulls(planes, hull_margin);
    frame
        .points
        .iter()
        .zip(classes)
        .enumerate()
        .filter(|(_, (_, c))| **c == Class::Reflection)
        .filter_map(|(i, (pt, _))| {
            let p = pt.position();
            let (k, _) = beams.first_hit(&p, None)?;
            Some((i, planes[k].plane.mirror(&p)))
        })
        .collect()
}
