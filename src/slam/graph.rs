//! From a tracking run to a pose-plane factor graph, and back.
//!
//! Variables: one pose per frame (the tracked pose as the initial value) and
//! one plane per surviving landmark (its fused world plane). Factors:
//!
//! - a relative-pose factor between consecutive frames: the frame-to-frame
//!   registration where it succeeded (independent of the map); where it
//!   failed, the tracked relative pose with a ten times looser noise, so
//!   the chain stays connected and the gauge stays the first pose's;
//! - one plane factor per logged observation (plane-to-plane or the
//!   point-to-plane scatter factor, per [`BackendParams::plane_factor`]),
//!   with the configured robust kernel.
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

/// The graph of a tracking run: poses `0..frames`, planes by landmark id.
/// Landmarks pruned from `map` and observations of them are left out.
pub fn tracking_graph(
    log: &TrackingLog,
    map: &PlaneMap,
    params: &BackendParams,
) -> Result<FactorGraph> {
    window_graph(log, 0..log.frames.len(), map, params)
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
    let frames = frames.start..frames.end.min(log.frames.len());
    let mut graph = FactorGraph::new();
    for k in frames.clone() {
        graph.values.poses.insert(k as u32, log.frames[k].pose);
    }
    // The log is in frame order: the window's observations are one slice.
    let lo = log.observations.partition_point(|o| o.frame < frames.start);
    let hi = log.observations.partition_point(|o| o.frame < frames.end);
    let observations: &[LandmarkObservation] = &log.observations[lo..hi.max(lo)];
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
    if frames.start > 0 {
        for l in map.landmarks.iter().filter(|l| planes.contains_key(&l.id)) {
            if l.first_frame < frames.start {
                graph.fixed.insert(Key::Plane(l.id as u32));
            }
        }
    }

    let odometry_info = diagonal_sqrt_info(
        params.odometry_translation_sigma,
        params.odometry_rotation_sigma,
    );
    for k in frames.start + 1..frames.end {
        let (measured, info) = match log.frames[k].odometry {
            Some(rel) => (rel, odometry_info),
            None => (
                log.frames[k - 1].pose.inverse() * log.frames[k].pose,
                odometry_info / FALLBACK_ODOMETRY_SCALE,
            ),
        };
        graph.add(AnyFactor::Between(Between::new(
            k as u32 - 1,
            k as u32,
            measured,
            info,
        )));
    }

    let plane_info = Matrix3::from_diagonal(&nalgebra::Vector3::new(
        1.0 / params.plane_normal_sigma,
        1.0 / params.plane_normal_sigma,
        1.0 / params.plane_offset_sigma,
    ));
    for obs in observations {
        if !planes.contains_key(&obs.landmark) {
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
    Ok(graph)
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

/// The optimised poses, in frame order (`fallback` for a frame the values
/// do not hold).
pub fn optimized_poses(values: &Values, fallback: &[Isometry3<f64>]) -> Vec<Isometry3<f64>> {
    fallback
        .iter()
        .enumerate()
        .map(|(k, p)| values.poses.get(&(k as u32)).copied().unwrap_or(*p))
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
