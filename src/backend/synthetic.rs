//! Deterministic synthetic pose-plane graphs for tests and benchmarks.
//!
//! A random-walk trajectory (1 m steps, wandering heading, small roll and
//! pitch) inside a box-shaped world whose planes all face the box interior
//! (so every observer sees them from the positive side, `d_s > 0`). Pose `i`
//! observes a sliding window of `observations_per_pose` consecutive planes,
//! so consecutive poses share most planes and the graph stays sparse.
//! Odometry is the true relative pose perturbed on the right; the initial
//! poses are the integrated noisy odometry (realistic drift) and each
//! landmark starts from its first observation.

use nalgebra::{
    Isometry3, Matrix3, Matrix6, Translation3, UnitQuaternion, Vector2, Vector3, Vector6,
};
use serde::{Deserialize, Serialize};

use super::backends::PlaneFactorKind;
use super::factors::{AnyFactor, Between, PlaneObservation, PointToPlane};
use super::graph::FactorGraph;
use super::unit3;
use super::variables::{PlaneVar, Values};
use crate::geometry::{se3, Plane};
use crate::rng::SplitMix64;
use crate::{Error, Result};

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SyntheticParams {
    /// Number of poses.
    pub poses: usize,
    /// Number of plane landmarks (0: `max(2·k, poses / 2)`).
    pub planes: usize,
    /// Plane observations per pose (`k`).
    pub observations_per_pose: usize,
    /// Plane factor type.
    pub factor: PlaneFactorKind,
    /// Seed of the generator.
    pub seed: u64,
    /// Half extent of the box in x and y (metres).
    pub half_extent: f64,
    /// Odometry translation noise (metres).
    pub odometry_translation_sigma: f64,
    /// Odometry rotation noise (radians).
    pub odometry_rotation_sigma: f64,
    /// Plane-to-plane normal noise (radians).
    pub plane_normal_sigma: f64,
    /// Plane-to-plane offset noise (metres).
    pub plane_offset_sigma: f64,
    /// Point-to-plane point noise (metres).
    pub point_sigma: f64,
    /// Points per point-to-plane observation.
    pub points_per_observation: usize,
}

impl Default for SyntheticParams {
    fn default() -> Self {
        Self {
            poses: 100,
            planes: 0,
            observations_per_pose: 10,
            factor: PlaneFactorKind::PlaneToPlane,
            seed: 1,
            half_extent: 30.0,
            odometry_translation_sigma: 0.05,
            odometry_rotation_sigma: 0.01,
            plane_normal_sigma: 0.01,
            plane_offset_sigma: 0.02,
            point_sigma: 0.03,
            points_per_observation: 20,
        }
    }
}

/// A generated graph (its stored values are the perturbed initial values)
/// and the ground truth.
#[derive(Debug, Clone)]
pub struct SyntheticGraph {
    /// The graph; `graph.values` holds the initial values.
    pub graph: FactorGraph,
    /// True poses and planes.
    pub truth: Values,
}

/// Generate a graph.
pub fn synthetic(p: &SyntheticParams) -> Result<SyntheticGraph> {
    let k = p.observations_per_pose;
    if p.poses < 2 || k == 0 {
        return Err(Error::Input(
            "synthetic graph needs at least 2 poses and 1 observation per pose".into(),
        ));
    }
    let m = if p.planes == 0 {
        (2 * k).max(p.poses / 2)
    } else {
        p.planes
    };
    if m < k {
        return Err(Error::Input(format!(
            "synthetic graph: {m} planes cannot give {k} observations per pose"
        )));
    }
    let positive = [
        p.half_extent,
        p.odometry_translation_sigma,
        p.odometry_rotation_sigma,
        p.plane_normal_sigma,
        p.plane_offset_sigma,
        p.point_sigma,
    ];
    if positive.iter().any(|v| !(*v > 0.0) || !v.is_finite()) {
        return Err(Error::Input(
            "synthetic graph: sizes and sigmas must be positive".into(),
        ));
    }
    let mut rng = SplitMix64::new(p.seed);
    let (w, zh) = (p.half_extent, 3.0);

    // Planes facing the box interior: d > max over the box of −n·x.
    let mut truth = Values::default();
    for j in 0..m {
        let n = if j % 5 == 4 {
            Vector3::new(
                0.1 * rng.normal(),
                0.1 * rng.normal(),
                if j % 2 == 0 { 1.0 } else { -1.0 },
            )
        } else {
            let a = std::f64::consts::TAU * rng.unit();
            Vector3::new(a.cos(), a.sin(), 0.2 * rng.normal())
        }
        .normalize();
        let d = w * (n.x.abs() + n.y.abs()) + zh * n.z.abs() + 1.0 + 10.0 * rng.unit();
        truth.planes.insert(j as u32, PlaneVar { normal: n, d });
    }

    // Random-walk trajectory inside the box.
    let mut heading = 0.0f64;
    let mut pos = Vector3::new(0.0, 0.0, 0.0);
    for i in 0..p.poses {
        if i > 0 {
            heading += 0.3 * rng.normal();
            let mut next = pos + Vector3::new(heading.cos(), heading.sin(), 0.05 * rng.normal());
            if next.x.abs() > 0.9 * w || next.y.abs() > 0.9 * w {
                heading += std::f64::consts::PI;
                next = pos + Vector3::new(heading.cos(), heading.sin(), 0.0);
            }
            next.z = next.z.clamp(-0.5 * zh, 0.5 * zh);
            pos = next;
        }
        let rot =
            UnitQuaternion::from_euler_angles(0.05 * rng.normal(), 0.05 * rng.normal(), heading);
        truth.poses.insert(
            i as u32,
            Isometry3::from_parts(Translation3::from(pos), rot),
        );
    }

    let mut graph = FactorGraph::new();
    // Odometry and integrated initial poses.
    let odo_info = Matrix6::from_diagonal(&Vector6::new(
        1.0 / p.odometry_translation_sigma,
        1.0 / p.odometry_translation_sigma,
        1.0 / p.odometry_translation_sigma,
        1.0 / p.odometry_rotation_sigma,
        1.0 / p.odometry_rotation_sigma,
        1.0 / p.odometry_rotation_sigma,
    ));
    let mut initial = Values::default();
    initial.poses.insert(0, truth.poses[&0]);
    for i in 1..p.poses as u32 {
        let z_true = truth.poses[&(i - 1)].inverse() * truth.poses[&i];
        let noise = Vector6::new(
            p.odometry_translation_sigma * rng.normal(),
            p.odometry_translation_sigma * rng.normal(),
            p.odometry_translation_sigma * rng.normal(),
            p.odometry_rotation_sigma * rng.normal(),
            p.odometry_rotation_sigma * rng.normal(),
            p.odometry_rotation_sigma * rng.normal(),
        );
        let z = z_true * se3::exp(&noise);
        graph.add(AnyFactor::Between(Between::new(i - 1, i, z, odo_info)));
        let prev = initial.poses[&(i - 1)];
        initial.poses.insert(i, prev * z);
    }

    // Plane observations.
    let plane_info = Matrix3::from_diagonal(&Vector3::new(
        1.0 / p.plane_normal_sigma,
        1.0 / p.plane_normal_sigma,
        1.0 / p.plane_offset_sigma,
    ));
    let mut points = Vec::with_capacity(p.points_per_observation.max(3));
    for i in 0..p.poses {
        let base = i * m / p.poses;
        let x = truth.poses[&(i as u32)];
        for o in 0..k {
            let j = ((base + o) % m) as u32;
            let world = truth.planes[&j].plane();
            let sensor = world.transformed(&x.inverse());
            let (factor, measured) = match p.factor {
                PlaneFactorKind::PlaneToPlane => {
                    let v = Vector2::new(rng.normal(), rng.normal()) * p.plane_normal_sigma;
                    let meas = Plane {
                        normal: unit3::retract(&sensor.normal, &v),
                        d: sensor.d + p.plane_offset_sigma * rng.normal(),
                    };
                    (
                        AnyFactor::PlaneObservation(PlaneObservation::new(
                            i as u32, j, meas, plane_info,
                        )),
                        meas,
                    )
                }
                PlaneFactorKind::PointToPlane => {
                    let b = unit3::basis(&sensor.normal);
                    let foot = -sensor.normal * sensor.d;
                    points.clear();
                    for _ in 0..p.points_per_observation.max(3) {
                        let uv = Vector2::new(6.0 * rng.unit() - 3.0, 6.0 * rng.unit() - 3.0);
                        points.push(foot + b * uv + sensor.normal * (p.point_sigma * rng.normal()));
                    }
                    let f = PointToPlane::from_points(i as u32, j, &points, p.point_sigma)?;
                    let fitted = f.fitted_plane().unwrap_or(sensor);
                    (AnyFactor::PointToPlane(f), fitted)
                }
            };
            graph.add(factor);
            if let std::collections::btree_map::Entry::Vacant(e) = initial.planes.entry(j) {
                e.insert(PlaneVar::from(
                    measured.transformed(&initial.poses[&(i as u32)]),
                ));
            }
        }
    }
    // Planes never observed (m larger than the windows cover) start at truth.
    for (j, pl) in &truth.planes {
        initial.planes.entry(*j).or_insert(*pl);
    }
    graph.values = initial;
    Ok(SyntheticGraph { graph, truth })
}

/// Mean translation error (metres) of `values`' poses against `truth`.
pub fn mean_translation_error(values: &Values, truth: &Values) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (id, x) in &values.poses {
        if let Some(t) = truth.poses.get(id) {
            sum += (x.translation.vector - t.translation.vector).norm();
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}
