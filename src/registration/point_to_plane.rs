//! Point-to-plane refinement of the directions the planes leave free.
//!
//! Each sample `p` of the frame (sensor frame, with its surface normal `n`)
//! is paired with the nearest point `m` of the local map at the current
//! pose `T = (R, t)`, and its residual is the distance of `m` from the
//! sample's tangent plane, `r = (R n)·(T p − m)`. With the right
//! perturbation `T · exp(δ)`, `δ = (ρ, φ)` (as the plane registration):
//!
//! `∂r/∂ρ = nᵀ`, `∂r/∂φ = (p × n + n × Rᵀ(T p − m))ᵀ`.
//!
//! Only the free directions move, and only those the samples observe: with
//! `P` the projector onto the free directions, the eigen-directions of
//! `P JᵀJ P` (unweighted: how many samples face along them) whose
//! information reaches the threshold are fixed by the points; the step
//! solves the Cauchy-weighted normal equations restricted to them. The
//! other directions keep the pose they came with.
//!
//! Each map point carries the index of the frame that contributed it; the
//! refinement reports the median of those over its last correspondences
//! ([`PointRefinement::anchor`]): the fixed directions are then a
//! measurement of the pose relative to that frame, which the back-end can
//! use (a relative-pose factor along them).

use nalgebra::{Isometry3, Matrix6, Point3, Vector3, Vector6};

use super::Degeneracy;
use crate::geometry::se3;

/// One surface sample of a frame: a point and the unit normal of the
/// surface around it, both in the sensor frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSample {
    /// The point.
    pub point: Point3<f64>,
    /// The surface normal (either sign).
    pub normal: Vector3<f64>,
}

/// The point-to-plane residual of `sample` against map point `m` at pose
/// `t`.
pub fn point_residual(t: &Isometry3<f64>, sample: &SurfaceSample, m: &Point3<f64>) -> f64 {
    (t.rotation * sample.normal).dot(&(t * sample.point - m))
}

/// The residual's Jacobian with respect to the right perturbation
/// `δ = (ρ, φ)` of `t`.
pub fn point_jacobian(t: &Isometry3<f64>, sample: &SurfaceSample, m: &Point3<f64>) -> Vector6<f64> {
    let n = sample.normal;
    let e = t.rotation.inverse() * (t * sample.point - m);
    let dphi = sample.point.coords.cross(&n) + n.cross(&e);
    Vector6::new(n.x, n.y, n.z, dphi.x, dphi.y, dphi.z)
}

/// The refinement stops when a step is shorter than this (tangent norm:
/// metres and radians).
const MIN_STEP: f64 = 1e-5;

/// What the point refinement did.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRefinement {
    /// The refined pose.
    pub pose: Isometry3<f64>,
    /// Samples paired with a map point at the last iteration.
    pub correspondences: usize,
    /// Free directions the points observed (and so fixed).
    pub fixed: usize,
    /// Iterations run.
    pub iterations: usize,
    /// The median frame index of the map points paired at the last
    /// iteration (`None` when nothing was fixed): the frame the fixed
    /// directions are measured against.
    pub anchor: Option<usize>,
    /// The fixed directions (orthonormal tangent vectors, sensor frame).
    pub fixed_directions: Vec<Vector6<f64>>,
}

/// Settings of [`refine_free_directions`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointRefineParams {
    /// Largest sample-to-map distance of a correspondence, m.
    pub max_correspondence: f64,
    /// Cauchy kernel scale, m.
    pub kernel_scale: f64,
    /// Gauss–Newton iterations.
    pub max_iterations: usize,
    /// Information a direction needs to be fixed.
    pub min_information: f64,
    /// A sample takes part when its residual moves along some free
    /// direction at least this share of what a sample facing straight
    /// along it would (`|n · v|` for a translation `v`). Samples are taken
    /// with the normal of their neighbouring beams: on the edges of a
    /// corridor (floor and ceiling meeting the walls, the rims of panes)
    /// that normal is a blend of two surfaces, half along the axis, and the
    /// nearest point of another scan lies on either surface. Such samples
    /// pull the axis by centimetres (glass-lined loop, frame 1 against
    /// frame 0: 1.6 cm off at 0.3, 0.0 at 0.7).
    pub min_alignment: f64,
}

/// Refine `pose` by point-to-plane registration of `samples` (sensor frame)
/// against a map (`nearest(p, max_distance)`: the map point nearest to
/// world point `p` and the index of the frame it came from), moving it
/// only within the span of `free` (orthonormal tangent directions, sensor
/// frame: the directions the planes left free) and only along the ones the
/// points observe.
pub fn refine_free_directions(
    samples: &[SurfaceSample],
    nearest: impl Fn(&Point3<f64>, f64) -> Option<(Point3<f64>, usize)>,
    pose: &Isometry3<f64>,
    free: &[Vector6<f64>],
    params: &PointRefineParams,
) -> PointRefinement {
    let projector: Matrix6<f64> = free.iter().map(|v| v * v.transpose()).sum();
    let mut out = PointRefinement {
        pose: *pose,
        correspondences: 0,
        fixed: 0,
        iterations: 0,
        anchor: None,
        fixed_directions: Vec::new(),
    };
    if free.is_empty() {
        return out;
    }
    // Only samples that face along some free direction can fix it (in a
    // corridor: end walls and door frames, not the long walls); the others
    // carry no information there, so they are not searched.
    let facing: Vec<&SurfaceSample> = samples
        .iter()
        .filter(|s| {
            let j = point_jacobian(&Isometry3::identity(), s, &s.point);
            free.iter().any(|v| {
                let lever = v.fixed_rows::<3>(0).norm()
                    + s.point.coords.norm() * v.fixed_rows::<3>(3).norm();
                j.dot(v).abs() >= params.min_alignment * lever
            })
        })
        .collect();
    let s2 = params.kernel_scale * params.kernel_scale;
    let mut sources = Vec::with_capacity(facing.len());
    for _ in 0..params.max_iterations {
        // Unweighted information decides which free directions the samples
        // observe (geometry: how many face along them); the kernel-weighted
        // system gives the step along those.
        let (mut info, mut h, mut g) = (Matrix6::zeros(), Matrix6::zeros(), Vector6::zeros());
        let mut pairs = 0;
        sources.clear();
        for s in facing.iter().copied() {
            let Some((m, source)) = nearest(&(out.pose * s.point), params.max_correspondence)
            else {
                continue;
            };
            sources.push(source);
            let r = point_residual(&out.pose, s, &m);
            let j = point_jacobian(&out.pose, s, &m);
            let w = 1.0 / (1.0 + r * r / s2);
            info += j * j.transpose();
            h += w * j * j.transpose();
            g += w * j * r;
            pairs += 1;
        }
        out.correspondences = pairs;
        let observed = Degeneracy::of(&(projector * info * projector), params.min_information);
        out.fixed = 6 - observed.count();
        if out.fixed == 0 {
            out.anchor = None;
            out.fixed_directions.clear();
            break;
        }
        out.fixed_directions = observed
            .eigenvalues
            .iter()
            .zip(&observed.eigenvectors)
            .filter(|(l, _)| **l > params.min_information)
            .map(|(_, v)| *v)
            .collect();
        let mid = sources.len() / 2;
        out.anchor = (!sources.is_empty()).then(|| *sources.select_nth_unstable(mid).1);
        let fixed: Matrix6<f64> = out.fixed_directions.iter().map(|v| v * v.transpose()).sum();
        let step = Degeneracy::of(&(fixed * h * fixed), 1e-12).solve(&(fixed * g));
        if !step.iter().all(|v| v.is_finite()) {
            break;
        }
        out.pose = se3::retract(&out.pose, &step);
        out.iterations += 1;
        if step.norm() < MIN_STEP {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slam::point_map::LocalPointMap;
    use nalgebra::{Translation3, UnitQuaternion};
    use proptest::prelude::*;

    proptest! {
        /// The analytic Jacobian matches central differences on the
        /// manifold (normal and point both rotate with the pose).
        #[test]
        fn jacobian_matches_central_differences(
            rx in -1.0..1.0f64, ry in -1.0..1.0f64, rz in -1.0..1.0f64,
            tx in -3.0..3.0f64, ty in -3.0..3.0f64, tz in -3.0..3.0f64,
            px in -5.0..5.0f64, py in -5.0..5.0f64, pz in -5.0..5.0f64,
            nx in -1.0..1.0f64, ny in -1.0..1.0f64, nz in 0.2..1.0f64,
            mx in -5.0..5.0f64, my in -5.0..5.0f64, mz in -5.0..5.0f64,
        ) {
            let t = Isometry3::from_parts(
                Translation3::new(tx, ty, tz),
                UnitQuaternion::from_scaled_axis(Vector3::new(rx, ry, rz)),
            );
            let sample = SurfaceSample {
                point: Point3::new(px, py, pz),
                normal: Vector3::new(nx, ny, nz).normalize(),
            };
            let m = Point3::new(mx, my, mz);
            let j = point_jacobian(&t, &sample, &m);
            let h = 1e-6;
            for k in 0..6 {
                let mut d = Vector6::zeros();
                d[k] = h;
                let plus = point_residual(&se3::retract(&t, &d), &sample, &m);
                let minus = point_residual(&se3::retract(&t, &-d), &sample, &m);
                let numeric = (plus - minus) / (2.0 * h);
                prop_assert!((numeric - j[k]).abs() < 1e-5 * (1.0 + j[k].abs()),
                    "k {k}: numeric {numeric}, analytic {}", j[k]);
            }
        }
    }

    /// A corridor along x (floor, walls) closed by an end wall at x = 10:
    /// the samples of a scan from x = 1 registered at a pose 0.3 m off
    /// along x, with only x free, come back to x = 1; with the end wall
    /// removed nothing observes x and the pose stays where it was.
    #[test]
    fn points_fix_the_free_direction_only_where_they_observe_it() {
        let scene = |with_end: bool| {
            let mut pts = Vec::new();
            for i in 0..100 {
                let x = 0.1 * i as f64;
                for k in 0..10 {
                    let z = 0.25 * k as f64;
                    pts.push((Point3::new(x, -1.0, z), Vector3::y()));
                    pts.push((Point3::new(x, 1.0, z), Vector3::y()));
                    pts.push((Point3::new(x, -1.0 + 0.2 * k as f64, 0.0), Vector3::z()));
                }
            }
            if with_end {
                for a in 0..20 {
                    for k in 0..10 {
                        pts.push((
                            Point3::new(10.0, -1.0 + 0.1 * a as f64, 0.25 * k as f64),
                            Vector3::x(),
                        ));
                    }
                }
            }
            pts
        };
        for with_end in [true, false] {
            let world = scene(with_end);
            let truth = Isometry3::translation(1.0, 0.0, 0.0);
            let mut map = LocalPointMap::new(0.5, 50);
            let as_samples = |pose: &Isometry3<f64>| -> Vec<SurfaceSample> {
                world
                    .iter()
                    .map(|(p, n)| SurfaceSample {
                        point: pose.inverse() * p,
                        normal: pose.inverse().rotation * n,
                    })
                    .collect()
            };
            map.insert(
                &as_samples(&Isometry3::identity()),
                &Isometry3::identity(),
                7,
            );
            let start = Isometry3::translation(1.3, 0.0, 0.0);
            let free = [Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0)];
            let params = PointRefineParams {
                max_correspondence: 0.5,
                kernel_scale: 0.05,
                max_iterations: 20,
                min_information: 20.0,
                min_alignment: 0.7,
            };
            let nearest = |p: &Point3<f64>, d: f64| map.nearest(p, d);
            let r = refine_free_directions(&as_samples(&truth), nearest, &start, &free, &params);
            if with_end {
                assert_eq!(r.fixed, 1);
                // Measured against the frame that built the map.
                assert_eq!(r.anchor, Some(7));
                assert_eq!(r.fixed_directions.len(), 1);
                assert!(r.fixed_directions[0][0].abs() > 0.999);
                assert!(
                    (r.pose.translation.x - 1.0).abs() < 1e-6,
                    "{}",
                    r.pose.translation.x
                );
            } else {
                assert_eq!(r.fixed, 0);
                assert_eq!(r.pose, start);
                assert_eq!(r.anchor, None);
            }
            // Only the free direction moved.
            assert!(r.pose.translation.y.abs() < 1e-12 && r.pose.translation.z.abs() < 1e-12);
        }
    }
}
