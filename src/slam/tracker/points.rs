//! Points where planes are not enough: the tracker's refinement of the
//! directions the plane registration left free against its local point
//! map.

use nalgebra::{Isometry3, Matrix6, SymmetricEigen, Unit, UnitQuaternion, Vector3, Vector6};

use super::Tracker;
use crate::frontend::FramePlane;
use crate::io::PlaneKind;
use crate::reflect::BoundedPlane;
use crate::registration::{refine_free_directions, PointRefineParams};
use crate::slam::log::PointsAnchor;
use crate::slam::point_map::ScanSamples;
use crate::slam::recovery::{search_heading_by_points, up_axis};
use crate::slam::tracker::FrameReport;

impl Tracker {
    /// Refine the directions of `pose` that the planes left free (per
    /// `report`'s degeneracy) against the local point map (first searching
    /// the heading when it is among them), then add the
    /// frame's samples to the map; samples behind a reflective plane of the
    /// frame or of the map are left out of both, unless every free
    /// direction lies in that plane (`parallel_reflective_deg`: there a
    /// mirror image moves like the real world). Returns the refined pose
    /// and, when the points fixed some direction, what they measured it
    /// against; counts the fixed directions in `report`.
    pub(super) fn refine_with_points(
        &mut self,
        planes: &[FramePlane],
        samples: &ScanSamples,
        pose: Isometry3<f64>,
        index: usize,
        report: &mut FrameReport,
    ) -> (Isometry3<f64>, Option<PointsAnchor>) {
        let pp = self.params.points;
        let to_sensor = pose.inverse();
        let free = report.free_directions();
        let masks = |bp: &BoundedPlane| {
            !pp.parallel_reflective_deg
                .is_some_and(|deg| in_plane(&free, bp, deg))
        };
        let reflective: Vec<BoundedPlane> = planes
            .iter()
            .filter(|fp| fp.kind == PlaneKind::Reflective)
            .map(|fp| BoundedPlane::from_points(fp.plane, fp.hull_3d()))
            .chain(
                self.map
                    .landmarks
                    .iter()
                    .filter(|l| l.kind == PlaneKind::Reflective)
                    .map(|l| l.bounded().transformed(&to_sensor)),
            )
            .filter(masks)
            .collect();
        let clean = samples.without_reflections(&reflective, pp.reflective_margin);
        let mut pose = pose;
        let mut anchor = None;
        let up = up_axis(planes);
        if heading_is_free(&free, &up) && !self.points.is_empty() {
            let points = &self.points;
            if let Some(yaw) = search_heading_by_points(
                &clean,
                |q, d| points.nearest(q, d),
                &pose,
                &up,
                pp.max_correspondence,
                pp.kernel_scale,
                pp.min_information,
            ) {
                pose *= UnitQuaternion::from_axis_angle(&up, yaw.to_radians());
                report.points_yaw_deg = Some(yaw);
            }
        }
        if !free.is_empty() {
            let params = PointRefineParams {
                max_correspondence: pp.max_correspondence,
                kernel_scale: pp.kernel_scale,
                max_iterations: pp.max_iterations,
                min_information: pp.min_information,
                min_alignment: pp.min_alignment,
            };
            let points = &self.points;
            let refined =
                refine_free_directions(&clean, |q, d| points.nearest(q, d), &pose, &free, &params);
            report.fixed_by_points = refined.fixed;
            pose = refined.pose;
            anchor = refined.anchor.map(|frame| PointsAnchor {
                frame,
                directions: refined.fixed_directions,
            });
        }
        self.points.insert(&clean, &pose, index);
        if self.params.loop_closure.enabled {
            self.clean_samples = clean;
        }
        self.points
            .forget_beyond(&pose.translation.vector.into(), pp.map_radius);
        (pose, anchor)
    }
}

/// Whether the heading (a turn about `up`, sensor frame) lies mostly in
/// the span of `free` (orthonormal tangent directions): the planes did not
/// fix it.
fn heading_is_free(free: &[Vector6<f64>], up: &Unit<Vector3<f64>>) -> bool {
    let turn = Vector6::new(0.0, 0.0, 0.0, up.x, up.y, up.z);
    free.iter().map(|d| d.dot(&turn).powi(2)).sum::<f64>() > 0.5
}

/// Whether every direction of `free` (tangent vectors `(ρ, φ)`, sensor
/// frame) is a translation lying in the plane of `bp` within `max_deg`
/// degrees (false when `free` is empty or `max_deg` is not positive).
fn in_plane(free: &[Vector6<f64>], bp: &BoundedPlane, max_deg: f64) -> bool {
    let sin = max_deg.to_radians().sin();
    max_deg > 0.0
        && !free.is_empty()
        && free.iter().all(|d| {
            let (rho, phi) = (d.fixed_rows::<3>(0), d.fixed_rows::<3>(3));
            phi.norm() <= sin * d.norm() && bp.plane.normal.dot(&rho).abs() <= sin * rho.norm()
        })
}

/// The part of the span of `free` (orthonormal) that `fixed` (orthonormal)
/// does not cover, as orthonormal directions: the eigenvectors of
/// `P_free (I − P_fixed) P_free` whose eigenvalue exceeds one half.
pub(crate) fn without_span(free: &[Vector6<f64>], fixed: &[Vector6<f64>]) -> Vec<Vector6<f64>> {
    if free.is_empty() || fixed.is_empty() {
        return free.to_vec();
    }
    let p_free: Matrix6<f64> = free.iter().map(|v| v * v.transpose()).sum();
    let p_fixed: Matrix6<f64> = fixed.iter().map(|v| v * v.transpose()).sum();
    let rest = p_free * (Matrix6::identity() - p_fixed) * p_free;
    let eig = SymmetricEigen::new(0.5 * (rest + rest.transpose()));
    let mut out: Vec<(f64, Vector6<f64>)> = (0..6)
        .filter(|&k| eig.eigenvalues[k] > 0.5)
        .map(|k| (eig.eigenvalues[k], eig.eigenvectors.column(k).into_owned()))
        .collect();
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out.into_iter().map(|(_, v)| v).collect()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};

    use super::*;
    use crate::geometry::Plane;

    /// The heading is free when the free directions turn about up more
    /// than they do anything else (together, if need be); a free
    /// translation or a turn about another axis leaves it fixed.
    #[test]
    fn the_heading_is_free_only_where_a_free_direction_turns_about_up() {
        let up = Vector3::z_axis();
        let yaw = Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let roll = Vector6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
        let along = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(heading_is_free(&[yaw], &up));
        assert!(heading_is_free(&[along, yaw], &up));
        assert!(!heading_is_free(&[], &up));
        assert!(!heading_is_free(&[along, roll], &up));
        // The turn shared by two orthonormal directions, each mostly
        // something else or mostly the turn.
        let a = Vector6::new(0.8, 0.0, 0.0, 0.0, 0.0, 0.6);
        let b = Vector6::new(-0.6, 0.0, 0.0, 0.0, 0.0, 0.8);
        assert!(heading_is_free(&[a, b], &up));
        assert!(!heading_is_free(&[a], &up));
    }

    /// Of the span of x and y, fixing x leaves y; fixing nothing leaves
    /// both.
    #[test]
    fn without_span_removes_the_fixed_directions() {
        let x = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let y = Vector6::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        let rest = without_span(&[x, y], &[x]);
        assert_eq!(rest.len(), 1);
        assert!((rest[0].dot(&y).abs() - 1.0).abs() < 1e-12);
        assert_eq!(without_span(&[x, y], &[]).len(), 2);
        assert!(without_span(&[x], &[x]).is_empty());
    }

    /// A wall at y = 2 facing the sensor, 10 m long and 3 m high.
    fn wall() -> BoundedPlane {
        let plane = Plane::new(Vector3::new(0.0, -1.0, 0.0), 2.0).expect("a unit normal");
        let corners = [(-5.0, -1.0), (5.0, -1.0), (5.0, 2.0), (-5.0, 2.0)]
            .map(|(x, z)| Point3::new(x, 2.0, z));
        BoundedPlane::from_points(plane, corners)
    }

    #[test]
    fn only_translations_within_the_plane_are_in_it() {
        let along = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let up = Vector6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
        let towards = Vector6::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        let yaw = Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let tilted = Vector6::new(1.0, 0.2, 0.0, 0.0, 0.0, 0.0).normalize();
        assert!(in_plane(&[along], &wall(), 5.0));
        assert!(in_plane(&[along, up], &wall(), 5.0));
        assert!(!in_plane(&[along, towards], &wall(), 5.0));
        assert!(!in_plane(&[yaw], &wall(), 5.0));
        // 11 degrees off the wall: in it at 15, not at 5.
        assert!(!in_plane(&[tilted], &wall(), 5.0));
        assert!(in_plane(&[tilted], &wall(), 15.0));
        // No free direction, or the rule off: nothing is in the plane.
        assert!(!in_plane(&[], &wall(), 5.0));
        assert!(!in_plane(&[along], &wall(), 0.0));
    }
}
