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

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector6};

use super::log::TrackingLog;
use crate::backend::{
    AnyFactor, BackendParams, Between, FactorGraph, GraphFactor, PlaneFactorKind, PlaneObservation,
    PlaneVar, PointToPlane, RobustKernel, Values,
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
    let mut graph = FactorGraph::new();
    for (k, f) in log.frames.iter().enumerate() {
        graph.values.poses.insert(k as u32, f.pose);
    }
    let planes: BTreeMap<usize, PlaneVar> = map
        .landmarks
        .iter()
        .map(|l| (l.id, PlaneVar::from(l.plane)))
        .collect();
    for (&id, &p) in &planes {
        graph.values.planes.insert(id as u32, p);
    }

    let odometry_info = diagonal_sqrt_info(
        params.odometry_translation_sigma,
        params.odometry_rotation_sigma,
    );
    for k in 1..log.frames.len() {
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
    for obs in &log.observations {
        if !planes.contains_key(&obs.landmark) || obs.frame >= log.frames.len() {
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
        let robust = match (params.plane_factor, params.robust) {
            // The scatter factor's whitened norm grows with √N even for a
            // perfect fit; the kernel's threshold is scaled to match.
            (PlaneFactorKind::PointToPlane, RobustKernel::Huber { k }) => RobustKernel::Huber {
                k: k * (obs.count as f64).sqrt(),
            },
            (PlaneFactorKind::PointToPlane, RobustKernel::Cauchy { k }) => RobustKernel::Cauchy {
                k: k * (obs.count as f64).sqrt(),
            },
            (_, kernel) => kernel,
        };
        graph
            .factors
            .push(GraphFactor::new(factor).with_robust(robust));
    }
    Ok(graph)
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
