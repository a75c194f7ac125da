//! From a tracking run to a pose-plane factor graph, and back.
//!
//! Variables: one pose per keyframe (the tracked pose as the initial value;
//! every frame is a keyframe unless `[slam] keyframe_move` or
//! `keyframe_turn_deg` say otherwise) and one plane per surviving landmark
//! (its fused world plane). Factors:
//!
//! - a relative-pose factor between consecutive keyframes: the frame-to-
//!   frame registrations between them composed where they succeeded
//!   (independent of the map); where one failed, the tracked relative pose
//!   with a ten times looser noise, so the chain stays connected and the
//!   gauge stays the first pose's;
//! - where tracking's point term fixed directions the planes left free, a
//!   relative-pose factor along those directions only, from the frame the
//!   matched map points came from to the frame
//!   ([`BackendParams::point_anchor_translation_sigma`]): the local point map's
//!   knowledge, which frame-to-frame odometry alone does not carry (in a
//!   corridor the planes give no position along it; odometry drifts there
//!   by its per-frame noise, the point map does not);
//! - one relative-pose factor per verified loop closure whose two frames
//!   are poses of the graph (the measured `T_from_to`, under the loop's
//!   robust kernel; [`crate::slam::loop_closure`]);
//! - one plane factor per logged observation (plane-to-plane or the
//!   point-to-plane scatter factor, per [`BackendParams::plane_factor`]),
//!   with the configured robust kernel; an observation whose points lie
//!   far from its landmark at the tracked pose
//!   ([`BackendParams::max_observation_rms`]) is a wrong association and
//!   is left out (a landmark left without observations is no variable).
//!
//! The first pose is fixed (the graph's automatic gauge): it defines the
//! world frame exactly as tracking did.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector6};

use super::log::{LandmarkObservation, TrackingLog};
use crate::backend::{
    AnyFactor, BackendParams, Between, FactorGraph, GraphFactor, Key, PlaneFactorKind,
    PlaneObservation, PlaneVar, PointToPlane, RobustKernel, Values,
};
use crate::map::PlaneMap;
use crate::Result;

/// Looser noise of a relative-pose factor taken from tracking itself.
const FALLBACK_ODOMETRY_SCALE: f64 = 10.0;

/// The rms distance of `obs`'s points from the plane `landmark` (world
/// frame) with the observing frame at `pose`.
fn observation_rms(obs: &LandmarkObservation, pose: &Isometry3<f64>, landmark: &PlaneVar) -> f64 {
    let plane = landmark.plane().transformed(&pose.inverse());
    let n = plane.normal;
    let spread = n.dot(&(obs.scatter * n)) / (obs.count.max(1) as f64);
    (spread.max(0.0) + plane.signed_distance(&obs.centroid).powi(2)).sqrt()
}

/// The graph of a tracking run: one pose per keyframe (every frame when
/// every frame is a keyframe), planes by landmark id. Landmarks pruned from
/// `map` and observations of them are left out.
pub fn tracking_graph(
    log: &TrackingLog,
    map: &PlaneMap,
    params: &BackendParams,
) -> Result<FactorGraph> {
    let keyframes: Vec<usize> = (0..log.frames.len())
        .filter(|&k| log.frames[k].keyframe)
        .collect();
    graph_of(log, &keyframes, map, params)
}

/// The graph of the frames `span` of a tracking run between two
/// keyframes (or after the last one), for placing the frames between them
/// once the keyframes and the map are optimised: the initial poses are
/// `poses`, the first and (when `last_is_keyframe`) last pose are held
/// fixed, and so is every plane.
pub fn segment_graph(
    log: &TrackingLog,
    span: Range<usize>,
    last_is_keyframe: bool,
    poses: &[Isometry3<f64>],
    map: &PlaneMap,
    params: &BackendParams,
) -> Result<FactorGraph> {
    let frames: Vec<usize> = span.collect();
    let mut graph = graph_of(log, &frames, map, params)?;
    for &k in &frames {
        graph.values.poses.insert(k as u32, poses[k]);
    }
    if let (Some(&first), Some(&last)) = (frames.first(), frames.last()) {
        graph.fixed.insert(Key::Pose(first as u32));
        if last_is_keyframe {
            graph.fixed.insert(Key::Pose(last as u32));
        }
    }
    let planes: Vec<u32> = graph.values.planes.keys().copied().collect();
    for id in planes {
        graph.fixed.insert(Key::Plane(id));
    }
    Ok(graph)
}

/// The graph of the frames `frames` of a tracking run (pose ids are frame
/// indices; the window's first pose is the gauge), with the landmarks they
/// observe.
pub fn window_graph(
    log: &TrackingLog,
    frames: Range<usize>,
    map: &PlaneMap,
    params: &BackendParams,
) -> Result<FactorGraph> {
    let frames: Vec<usize> = (frames.start..frames.end.min(log.frames.len())).collect();
    graph_of(log, &frames, map, params)
}

/// The graph of the poses `frames` (increasing frame indices) of a tracking
/// run, with the landmarks they observe. Consecutive poses are tied by
/// their odometry; poses further apart (keyframes) by the odometry of the
/// frames between them composed, its noise growing with their number.
fn graph_of(
    log: &TrackingLog,
    frames: &[usize],
    map: &PlaneMap,
    params: &BackendParams,
) -> Result<FactorGraph> {
    let mut graph = FactorGraph::new();
    let (Some(&first), Some(&last)) = (frames.first(), frames.last()) else {
        return Ok(graph);
    };
    for &k in frames {
        graph.values.poses.insert(k as u32, log.frames[k].pose);
    }
    // The log is in frame order: the observations of the span are one
    // slice, of which the poses' own are kept.
    let lo = log.observations.partition_point(|o| o.frame < first);
    let hi = log.observations.partition_point(|o| o.frame <= last);
    let observations: Vec<&LandmarkObservation> = log.observations[lo..hi.max(lo)]
        .iter()
        .filter(|o| frames.binary_search(&o.frame).is_ok())
        .collect();
    let seen: BTreeSet<usize> = observations.iter().map(|o| o.landmark).collect();
    let planes: BTreeMap<usize, PlaneVar> = map
        .landmarks
        .iter()
        .filter(|l| seen.contains(&l.id))
        .map(|l| (l.id, PlaneVar::from(l.plane)))
        .collect();
    for (&id, &p) in &planes {
        graph.values.planes.insert(id as u32, p);
    }
    // Landmarks seen before the window carry the evidence of frames the
    // window does not hold: they stay where that evidence put them (a
    // window free to move them would forget it).
    if first > 0 {
        for l in map.landmarks.iter().filter(|l| planes.contains_key(&l.id)) {
            if l.first_frame < first {
                graph.fixed.insert(Key::Plane(l.id as u32));
            }
        }
    }

    let odometry_info = diagonal_sqrt_info(
        params.odometry_translation_sigma,
        params.odometry_rotation_sigma,
    );
    let free_info = match (
        params.odometry_free_translation_sigma,
        params.odometry_free_rotation_sigma,
    ) {
        (Some(t), Some(r)) => Some(diagonal_sqrt_info(t, r)),
        _ => None,
    };
    for pair in frames.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let mut measured = Isometry3::identity();
        let mut fallback = false;
        for k in a + 1..=b {
            measured *= match log.frames[k].odometry {
                Some(rel) => rel,
                None => {
                    fallback = true;
                    log.frames[k - 1].pose.inverse() * log.frames[k].pose
                }
            };
        }
        // Independent per-frame noise: the variance grows with the count.
        let mut info = odometry_info / ((b - a) as f64).sqrt();
        if fallback {
            info /= FALLBACK_ODOMETRY_SCALE;
        }
        if let Some(free_info) = free_info {
            let free = free_directions(log, a, b);
            if !free.is_empty() {
                info = loosen(&info, &(free_info / ((b - a) as f64).sqrt()), &free);
            }
        }
        graph.add(AnyFactor::Between(Between::new(
            a as u32, b as u32, measured, info,
        )));
    }
    // Loop closures whose two frames are poses of this graph.
    for l in &log.loops {
        if frames.binary_search(&l.from).is_ok() && frames.binary_search(&l.to).is_ok() {
            let factor = AnyFactor::Between(Between::new(
                l.from as u32,
                l.to as u32,
                l.relative,
                l.sqrt_info,
            ));
            graph
                .factors
                .push(GraphFactor::new(factor).with_robust(l.robust));
        }
    }
    if let (Some(t), Some(r)) = (
        params.point_anchor_translation_sigma,
        params.point_anchor_rotation_sigma,
    ) {
        for &k in frames {
            if let Some(f) = anchor_factor(log, frames, k, (t, r)) {
                graph.add(f);
            }
        }
    }

    let plane_info = Matrix3::from_diagonal(&nalgebra::Vector3::new(
        1.0 / params.plane_normal_sigma,
        1.0 / params.plane_normal_sigma,
        1.0 / params.plane_offset_sigma,
    ));
    for obs in observations {
        let Some(landmark) = planes.get(&obs.landmark) else {
            continue;
        };
        if params
            .max_observation_rms
            .is_some_and(|max| observation_rms(obs, &log.frames[obs.frame].pose, landmark) > max)
        {
            continue;
        }
        let (x, l) = (obs.frame as u32, obs.landmark as u32);
        let factor = match params.plane_factor {
            PlaneFactorKind::PlaneToPlane => {
                AnyFactor::PlaneObservation(PlaneObservation::new(x, l, obs.plane, plane_info))
            }
            PlaneFactorKind::PointToPlane => AnyFactor::PointToPlane(PointToPlane::new(
                x,
                l,
                obs.count as f64,
                obs.centroid.coords,
                obs.scatter,
                params.point_sigma,
            )?),
        };
        let robust = match params.plane_factor {
            PlaneFactorKind::PlaneToPlane => params.robust,
            PlaneFactorKind::PointToPlane => scatter_kernel(params, obs),
        };
        graph
            .factors
            .push(GraphFactor::new(factor).with_robust(robust));
    }
    // A landmark whose every observation the gates left out is no variable
    // (nothing would constrain it).
    let used: BTreeSet<Key> = graph
        .factors
        .iter()
        .flat_map(|f| {
            crate::backend::factors::Factor::keys(&f.factor)
                .iter()
                .copied()
        })
        .collect();
    graph
        .values
        .planes
        .retain(|&id, _| used.contains(&Key::Plane(id)));
    graph
        .fixed
        .retain(|k| !matches!(k, Key::Plane(_)) || used.contains(k));
    Ok(graph)
}

/// The directions of the odometry from frame `a` to frame `b` that nothing
/// measured ([`TrackedFrame::odometry_free`](super::log::TrackedFrame)),
/// in frame `b`'s tangent: each frame's, moved there by the adjoint of the
/// tracked motion from it to `b` (`exp(v)` at frame `k` is
/// `exp(Ad(T_b_k) v)` at `b`), orthonormalised.
fn free_directions(log: &TrackingLog, a: usize, b: usize) -> Vec<Vector6<f64>> {
    let mut span = Matrix6::zeros();
    let mut any = false;
    for k in a + 1..=b {
        let f = &log.frames[k];
        if f.odometry_free.is_empty() {
            continue;
        }
        let to_b = log.frames[b].pose.inverse() * f.pose;
        let ad = crate::geometry::se3::adjoint(&to_b);
        for v in &f.odometry_free {
            let w = ad * v;
            let n = w.norm();
            if n > 1e-12 {
                span += (w / n) * (w / n).transpose();
                any = true;
            }
        }
    }
    if !any {
        return Vec::new();
    }
    let eig = nalgebra::SymmetricEigen::new(span);
    let mut out: Vec<(f64, Vector6<f64>)> = (0..6)
        .filter(|&k| eig.eigenvalues[k] > 0.5)
        .map(|k| (eig.eigenvalues[k], eig.eigenvectors.column(k).into_owned()))
        .collect();
    out.sort_by(|x, y| y.0.total_cmp(&x.0));
    out.into_iter().map(|(_, v)| v).collect()
}

/// `info` (square-root information of a relative pose) with the residual's
/// components along `free` (orthonormal tangent vectors) whitened by
/// `free_info` instead: `S (I − P) + S_free P`, `P` the projector onto
/// `free`.
fn loosen(info: &Matrix6<f64>, free_info: &Matrix6<f64>, free: &[Vector6<f64>]) -> Matrix6<f64> {
    let p: Matrix6<f64> = free.iter().map(|v| v * v.transpose()).sum();
    info * (Matrix6::identity() - p) + free_info * p
}

/// The point term's measurement of frame `k` as a factor: the tracked
/// relative pose from its anchor frame (or the last graph frame before it,
/// when the anchor is not in `frames`) with information only along the
/// fixed directions, whitened by the point-anchor sigmas. `None` without
/// an anchor or when no frame of `frames` precedes it.
fn anchor_factor(
    log: &TrackingLog,
    frames: &[usize],
    k: usize,
    sigmas: (f64, f64),
) -> Option<AnyFactor> {
    let anchor = log.frames[k].points_anchor.as_ref()?;
    // The last pose of the graph at or before the anchor frame; in a
    // window that starts after it, the window's first pose: both are fixed
    // there, so the tracked relative pose carries the points' measurement
    // (without it the window knows the free directions only from the
    // odometry, which there is the motion model's prediction).
    let a = frames[..frames.partition_point(|&f| f <= anchor.frame.min(k))]
        .last()
        .or(frames.first())
        .copied()
        .filter(|&a| a < k)?;
    let measured = log.frames[a].pose.inverse() * log.frames[k].pose;
    let (t, r) = (1.0 / sigmas.0, 1.0 / sigmas.1);
    let weights = Vector6::new(t, t, t, r, r, r);
    let mut info = Matrix6::zeros();
    for (row, v) in anchor.directions.iter().take(6).enumerate() {
        // The residual's component along v, scaled by the noise of its
        // translation and rotation parts.
        let scale = (v.component_mul(&weights)).norm();
        info.set_row(row, &(v.transpose() * scale));
    }
    Some(AnyFactor::Between(Between::new(
        a as u32, k as u32, measured, info,
    )))
}

/// The robust kernel of a point-to-plane factor. Its whitened norm is
/// `√N · rms / σ` for a correct association (`rms` the inliers' distance to
/// their own plane), not about 1 as for a plane-to-plane factor, so the
/// kernel's threshold is scaled by it: an association is down-weighted once
/// the landmark lies farther from the inliers than `k` times their own
/// scatter (with a 1 cm floor on the rms).
fn scatter_kernel(params: &BackendParams, obs: &LandmarkObservation) -> RobustKernel {
    let n = obs.count.max(1) as f64;
    let lambda_min = nalgebra::SymmetricEigen::new(obs.scatter)
        .eigenvalues
        .min()
        .max(0.0);
    let rms = (lambda_min / n).sqrt().max(0.01);
    let scale = n.sqrt() * rms / params.point_sigma;
    match params.robust {
        RobustKernel::Huber { k } => RobustKernel::Huber { k: k * scale },
        RobustKernel::Cauchy { k } => RobustKernel::Cauchy { k: k * scale },
        other => other,
    }
}

/// Square-root information of independent translation and rotation noise
/// in the `(ρ, φ)` ordering.
pub fn diagonal_sqrt_info(translation_sigma: f64, rotation_sigma: f64) -> Matrix6<f64> {
    let t = 1.0 / translation_sigma;
    let r = 1.0 / rotation_sigma;
    Matrix6::from_diagonal(&Vector6::new(t, t, t, r, r, r))
}

/// The optimised poses, in frame order. A frame the values hold takes its
/// value; any other (a frame between keyframes) keeps its tracked pose
/// `fallback` relative to the last frame before it that the values hold.
pub fn optimized_poses(values: &Values, fallback: &[Isometry3<f64>]) -> Vec<Isometry3<f64>> {
    let mut correction = Isometry3::identity();
    fallback
        .iter()
        .enumerate()
        .map(|(k, p)| match values.poses.get(&(k as u32)) {
            Some(v) => {
                correction = v * p.inverse();
                *v
            }
            None => correction * p,
        })
        .collect()
}

/// Write the optimised planes back into the map's landmarks (boundaries are
/// projected onto the moved planes).
pub fn update_map(map: &mut PlaneMap, values: &Values) {
    for l in &mut map.landmarks {
        let Some(p) = values.planes.get(&(l.id as u32)) else {
            continue;
        };
        let plane = p.plane();
        for v in &mut l.boundary {
            *v = plane.project(v);
        }
        l.plane = plane;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slam::log::TrackedFrame;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    /// A log of `n` frames moving 0.1 m and turning 1 degree per frame,
    /// every frame's odometry measured; `keyframes` marks the keyframes.
    fn log(n: usize, keyframes: &[usize]) -> TrackingLog {
        let step = Isometry3::from_parts(
            Translation3::new(0.1, 0.0, 0.0),
            UnitQuaternion::from_scaled_axis(Vector3::z() * 1f64.to_radians()),
        );
        let mut pose = Isometry3::identity();
        let frames = (0..n)
            .map(|k| {
                if k > 0 {
                    pose *= step;
                }
                TrackedFrame {
                    pose,
                    odometry: (k > 0).then_some(step),
                    odometry_free: Vec::new(),
                    keyframe: keyframes.contains(&k),
                    points_anchor: None,
                }
            })
            .collect();
        TrackingLog {
            frames,
            observations: Vec::new(),
            loops: Vec::new(),
        }
    }

    /// Keyframes are tied by the odometry between them composed, its noise
    /// growing with the number of frames composed; with every frame a
    /// keyframe the graph is the frame-by-frame chain.
    #[test]
    fn keyframes_are_tied_by_composed_odometry() {
        let params = BackendParams::default();
        let every = tracking_graph(&log(5, &[0, 1, 2, 3, 4]), &PlaneMap::new(), &params).unwrap();
        assert_eq!(every.values.poses.len(), 5);
        assert_eq!(every.factors.len(), 4);
        let l = log(5, &[0, 3, 4]);
        let graph = tracking_graph(&l, &PlaneMap::new(), &params).unwrap();
        assert_eq!(
            graph.values.poses.keys().copied().collect::<Vec<_>>(),
            vec![0, 3, 4]
        );
        let AnyFactor::Between(first) = &graph.factors[0].factor else {
            panic!("a relative-pose factor");
        };
        let truth = l.frames[0].pose.inverse() * l.frames[3].pose;
        assert!((first.measured.translation.vector - truth.translation.vector).norm() < 1e-12);
        assert!(first.measured.rotation.angle_to(&truth.rotation) < 1e-12);
        let AnyFactor::Between(second) = &graph.factors[1].factor else {
            panic!("a relative-pose factor");
        };
        let ratio = second.sqrt_info[(0, 0)] / first.sqrt_info[(0, 0)];
        assert!((ratio - 3f64.sqrt()).abs() < 1e-12, "{ratio}");
    }

    /// A frame whose free direction (x) the points fixed against frame 2
    /// is tied to frame 2 by a factor along x only, with the point-anchor
    /// noise; with the sigmas at 0 there is no such factor, and an anchor
    /// outside the graph's frames moves to the last frame before it.
    #[test]
    fn a_points_anchor_is_a_factor_along_the_fixed_directions_only() {
        let mut l = log(6, &[0, 1, 2, 3, 4, 5]);
        l.frames[5].points_anchor = Some(crate::slam::log::PointsAnchor {
            frame: 2,
            directions: vec![Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0)],
        });
        let params = BackendParams {
            point_anchor_translation_sigma: Some(0.04),
            ..BackendParams::default()
        };
        let graph = tracking_graph(&l, &PlaneMap::new(), &params).unwrap();
        assert_eq!(graph.factors.len(), 6);
        let AnyFactor::Between(f) = &graph.factors[5].factor else {
            panic!("a relative-pose factor");
        };
        assert_eq!(
            crate::backend::factors::Factor::keys(f),
            &[Key::Pose(2), Key::Pose(5)]
        );
        let truth = l.frames[2].pose.inverse() * l.frames[5].pose;
        assert!((f.measured.translation.vector - truth.translation.vector).norm() < 1e-12);
        assert!((f.sqrt_info[(0, 0)] - 25.0).abs() < 1e-12);
        assert_eq!(f.sqrt_info.row(0).iter().filter(|v| **v != 0.0).count(), 1);
        assert!(f.sqrt_info.rows(1, 5).iter().all(|v| *v == 0.0));
        let off = BackendParams {
            point_anchor_translation_sigma: None,
            point_anchor_rotation_sigma: None,
            ..params
        };
        assert_eq!(
            tracking_graph(&l, &PlaneMap::new(), &off)
                .unwrap()
                .factors
                .len(),
            5
        );
        // Keyframes 0, 1, 4, 5: the anchor (frame 2) moves to frame 1.
        for (k, f) in l.frames.iter_mut().enumerate() {
            f.keyframe = [0, 1, 4, 5].contains(&k);
        }
        let graph = tracking_graph(&l, &PlaneMap::new(), &params).unwrap();
        let keys: Vec<_> = graph
            .factors
            .iter()
            .map(|f| crate::backend::factors::Factor::keys(&f.factor).to_vec())
            .collect();
        assert!(keys.contains(&vec![Key::Pose(1), Key::Pose(5)]), "{keys:?}");
    }

    /// Along a direction the odometry left free, its factor carries the
    /// free-direction noise; elsewhere, and with the free sigmas at 0, the
    /// odometry's.
    #[test]
    fn free_odometry_directions_get_the_free_noise() {
        let mut l = log(3, &[0, 1, 2]);
        l.frames[2].odometry_free = vec![Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0)];
        let params = BackendParams {
            odometry_translation_sigma: 0.01,
            odometry_free_translation_sigma: Some(0.5),
            odometry_free_rotation_sigma: Some(0.1),
            ..BackendParams::default()
        };
        let graph = tracking_graph(&l, &PlaneMap::new(), &params).unwrap();
        let AnyFactor::Between(f) = &graph.factors[1].factor else {
            panic!("a relative-pose factor");
        };
        assert!((f.sqrt_info[(0, 0)] - 2.0).abs() < 1e-9, "{}", f.sqrt_info);
        assert!((f.sqrt_info[(1, 1)] - 100.0).abs() < 1e-9);
        let AnyFactor::Between(first) = &graph.factors[0].factor else {
            panic!("a relative-pose factor");
        };
        assert!((first.sqrt_info[(0, 0)] - 100.0).abs() < 1e-9);
        let off = BackendParams {
            odometry_free_translation_sigma: None,
            odometry_free_rotation_sigma: None,
            ..params
        };
        let graph = tracking_graph(&l, &PlaneMap::new(), &off).unwrap();
        let AnyFactor::Between(f) = &graph.factors[1].factor else {
            panic!("a relative-pose factor");
        };
        assert!((f.sqrt_info[(0, 0)] - 100.0).abs() < 1e-9);
    }

    /// Frames between keyframes follow their keyframe's correction.
    #[test]
    fn frames_between_keyframes_move_with_their_keyframe() {
        let l = log(6, &[0, 3]);
        let tracked: Vec<Isometry3<f64>> = l.frames.iter().map(|f| f.pose).collect();
        let shift = Isometry3::translation(0.0, 0.5, 0.0);
        let mut values = Values::default();
        values.poses.insert(0, tracked[0]);
        values.poses.insert(3, shift * tracked[3]);
        let poses = optimized_poses(&values, &tracked);
        for k in 0..3 {
            assert!((poses[k].translation.vector - tracked[k].translation.vector).norm() < 1e-12);
        }
        for k in 3..6 {
            let expected = shift * tracked[k];
            assert!((poses[k].translation.vector - expected.translation.vector).norm() < 1e-12);
        }
    }
}
