//! Recovery of a frame whose frame-to-frame registration failed: a search
//! over the heading.
//!
//! Frame-to-frame matching compares planes moved by the predicted relative
//! pose, with gates of 0.1 m on the offset and 0.71 m on the centroid
//! distance. An error in the predicted heading moves a plane's centroid
//! 5 m away by 0.09 m per degree, so a turn the motion model did not
//! foresee — a sharp turn at 5 Hz, a turn during a gap of dropped frames —
//! leaves no pair within the gates, registration fails, and the frame
//! falls back to the prediction: its planes then enter the map rotated and
//! the rest of the run is tracked in a rotated world (the lobby at 5 Hz
//! before this: ATE 0.27 m from one such frame).
//!
//! The heading is the uncertain part of a prediction (a translation error
//! of a few decimetres still passes the gates of all but the smallest
//! planes; a turn does not), so the search tries headings about the
//! frame's up axis (the ground plane's normal, else the sensor's z) at
//! `yaw_step_deg` steps out to `max_yaw_deg` on both sides and keeps the
//! registration with the most inliers (the smaller turn on a tie). Only
//! failed frames pay for it.

use nalgebra::{Isometry3, Point3, Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::frontend::FramePlane;
use crate::io::PlaneKind;
use crate::registration::{
    match_planes, point_residual, register, GaussNewtonParams, MatchCriteria, MismatchRejector,
    Registration, SurfaceSample,
};

/// Settings of the heading search (`[slam.recovery]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecoveryParams {
    /// Search the heading when frame-to-frame registration fails.
    pub enabled: bool,
    /// Largest heading change tried on each side of the prediction,
    /// degrees.
    pub max_yaw_deg: f64,
    /// Step between the headings tried, degrees: [`YAW_STEP_DEG`].
    #[serde(skip, default = "yaw_step_deg")]
    pub yaw_step_deg: f64,
    /// A registration with fewer inliers (plane pairs) than this counts as
    /// failed (and triggers the search), and the search must reach it:
    /// [`MIN_INLIERS`].
    #[serde(skip, default = "min_inliers")]
    pub min_inliers: usize,
}

/// Step between the headings the search tries, degrees.
pub const YAW_STEP_DEG: f64 = 10.0;

/// A frame-to-frame registration with fewer inlier plane pairs failed (and
/// starts the heading search, which must reach it): three planes fix a pose.
pub const MIN_INLIERS: usize = 3;

fn yaw_step_deg() -> f64 {
    YAW_STEP_DEG
}

fn min_inliers() -> usize {
    MIN_INLIERS
}

impl Default for RecoveryParams {
    /// `[slam.recovery]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.recovery")
    }
}

/// A recovered frame-to-frame registration.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered {
    /// The registration (current frame to previous frame).
    pub registration: Registration,
    /// The heading change from the prediction where it was found, degrees.
    pub yaw_deg: f64,
}

/// The up direction of a frame (sensor frame): the ground plane's normal
/// (the largest ground plane) or, without one, the sensor's z axis.
pub fn up_axis(planes: &[FramePlane]) -> Unit<Vector3<f64>> {
    planes
        .iter()
        .filter(|p| p.kind == PlaneKind::Ground)
        .max_by(|a, b| a.area.total_cmp(&b.area))
        .map_or_else(Vector3::z_axis, |g| Unit::new_normalize(g.plane.normal))
}

/// The headings tried, in order: `±step`, `±2 step`, ... out to `max`
/// (degrees; the prediction itself, 0, is not repeated).
pub fn yaw_candidates(params: &RecoveryParams) -> Vec<f64> {
    let mut out = Vec::new();
    if !(params.yaw_step_deg > 0.0) || !(params.max_yaw_deg > 0.0) {
        return out;
    }
    let steps = (params.max_yaw_deg / params.yaw_step_deg).floor() as usize;
    for k in 1..=steps {
        let a = k as f64 * params.yaw_step_deg;
        out.push(a);
        out.push(-a);
    }
    out
}

/// Everything a frame-to-frame registration needs besides the planes and
/// the prior.
pub struct RegistrationContext<'a> {
    /// The mismatch rejector.
    pub rejector: &'a dyn MismatchRejector,
    /// Refinement settings.
    pub gauss_newton: &'a GaussNewtonParams,
    /// Frame-to-frame matching criteria.
    pub criteria: &'a MatchCriteria,
    /// Inlier normal cosine of the re-selection.
    pub inlier_cos: f64,
    /// Inlier offset of the re-selection, m.
    pub inlier_offset: f64,
    /// Seed of the rejector.
    pub seed: u64,
}

/// Search the heading of `current` (sensor frame) against `previous`
/// around the predicted relative pose `rel_prior` (current to previous):
/// the registration with the most inliers, at least
/// `params.min_inliers`, over the headings of [`yaw_candidates`]; `None`
/// when none reaches it.
pub fn recover_heading(
    current: &[FramePlane],
    previous: &[FramePlane],
    rel_prior: &Isometry3<f64>,
    params: &RecoveryParams,
    ctx: &RegistrationContext<'_>,
) -> Option<Recovered> {
    let up = up_axis(current);
    let mut best: Option<Recovered> = None;
    for yaw in yaw_candidates(params) {
        let turn = UnitQuaternion::from_axis_angle(&up, yaw.to_radians());
        let prior = rel_prior * Isometry3::from_parts(Default::default(), turn);
        let pairs = match_planes(current, previous, &prior, ctx.criteria);
        if pairs.len() < params.min_inliers.max(1) {
            continue;
        }
        let Some(reg) = register(
            &pairs,
            &prior,
            ctx.rejector,
            ctx.gauss_newton,
            ctx.inlier_cos,
            ctx.inlier_offset,
            ctx.seed,
        ) else {
            continue;
        };
        let better = best
            .as_ref()
            .is_none_or(|b| reg.inliers.len() > b.registration.inliers.len());
        if reg.inliers.len() >= params.min_inliers && better {
            best = Some(Recovered {
                registration: reg,
                yaw_deg: yaw,
            });
        }
    }
    best
}

/// Largest heading change the point search tries on each side of the pose
/// the planes gave, degrees: three frames of the fastest turns of the
/// families' paths (90 deg/s at 10 Hz), a turn the motion model did not
/// foresee from a standstill.
pub const POINT_SEARCH_MAX_YAW_DEG: f64 = 30.0;

/// Step between the headings the point search tries, degrees: half a step
/// moves a sample 10 m away by 0.09 m, well within the reach of the point
/// refinement that follows.
pub const POINT_SEARCH_STEP_DEG: f64 = 1.0;

/// Samples the point search scores each heading with, at most (evenly
/// spaced through the frame's samples).
pub const POINT_SEARCH_SAMPLES: usize = 500;

/// The heading about `up` (sensor frame) that best lays `samples` (sensor
/// frame) onto a point map at `pose`: the turn, in degrees, of the heading
/// whose samples lie nearest the map's surfaces (the sum over samples of
/// a Cauchy weight of the point-to-plane distance to the nearest map
/// point within `max_distance`, `kernel_scale` m), searched at
/// [`POINT_SEARCH_STEP_DEG`] out to [`POINT_SEARCH_MAX_YAW_DEG`] on both
/// sides and placed between the steps by the parabola through the best
/// and its neighbours; `None` when no turn lays them better than the pose
/// itself, or
/// when the best lays fewer than `min_support` samples (weighted) on the
/// map: a frame that sees almost no surface (a turn towards an open
/// street) keeps the motion model's heading rather than the best fit of a
/// few samples.
///
/// This is the frame-to-map counterpart of [`recover_heading`] for frames
/// with too few planes to register: a forward-looking sensor (the Livox
/// Avia's 70 deg field) sees one to five planes, and a turn at a corner
/// outruns the point refinement's correspondences (9 deg a frame moves a
/// wall 10 m away by 1.6 m).
pub fn search_heading_by_points(
    samples: &[SurfaceSample],
    nearest: impl Fn(&Point3<f64>, f64) -> Option<(Point3<f64>, usize)>,
    pose: &Isometry3<f64>,
    up: &Unit<Vector3<f64>>,
    max_distance: f64,
    kernel_scale: f64,
    min_support: f64,
) -> Option<f64> {
    let stride = samples.len().div_ceil(POINT_SEARCH_SAMPLES).max(1);
    let scored: Vec<&SurfaceSample> = samples.iter().step_by(stride).collect();
    let c2 = kernel_scale * kernel_scale;
    let score = |yaw: f64| -> f64 {
        let turned = pose * UnitQuaternion::from_axis_angle(up, yaw.to_radians());
        scored
            .iter()
            .filter_map(|s| {
                let (m, _) = nearest(&(turned * s.point), max_distance)?;
                let r = point_residual(&turned, s, &m);
                Some(1.0 / (1.0 + r * r / c2))
            })
            .sum()
    };
    let params = RecoveryParams {
        enabled: true,
        max_yaw_deg: POINT_SEARCH_MAX_YAW_DEG,
        yaw_step_deg: POINT_SEARCH_STEP_DEG,
        min_inliers: 0,
    };
    let mut best = (0.0, score(0.0));
    for yaw in yaw_candidates(&params) {
        // The candidates go outwards: a later one must be strictly better.
        let s = score(yaw);
        if s > best.1 {
            best = (yaw, s);
        }
    }
    if best.0 == 0.0 || best.1 < min_support {
        return None;
    }
    // Between the steps: the vertex of the parabola through the best and
    // its two neighbours (the score is smooth at the scale of a step).
    let step = POINT_SEARCH_STEP_DEG;
    let (below, above) = (score(best.0 - step), score(best.0 + step));
    let curvature = below - 2.0 * best.1 + above;
    let offset = if curvature < 0.0 {
        (0.5 * (below - above) / curvature * step).clamp(-0.5 * step, 0.5 * step)
    } else {
        0.0
    };
    Some(best.0 + offset)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slam::point_map::LocalPointMap;

    /// An L-shaped room corner seen from the origin: two walls (x = 6,
    /// y = 4) and a floor patch, as surface samples (world frame).
    fn corner() -> Vec<SurfaceSample> {
        let mut out = Vec::new();
        for i in 0..40 {
            for k in 0..8 {
                let (a, z) = (-4.0 + 0.2 * i as f64, -1.0 + 0.3 * k as f64);
                out.push(SurfaceSample {
                    point: Point3::new(6.0, a, z),
                    normal: Vector3::x(),
                });
                out.push(SurfaceSample {
                    point: Point3::new(a + 2.0, 4.0, z),
                    normal: Vector3::y(),
                });
            }
            out.push(SurfaceSample {
                point: Point3::new(1.0 + 0.1 * i as f64, 0.5, -1.0),
                normal: Vector3::z(),
            });
        }
        out
    }

    #[test]
    fn the_point_search_finds_a_turn_the_prediction_missed() {
        let world = corner();
        let mut map = LocalPointMap::new(0.5, 20);
        map.insert(&world, &Isometry3::identity(), 0);
        let nearest = |p: &Point3<f64>, d: f64| map.nearest(p, d);
        // The sensor turned 12.4 deg to the left; the prediction says it
        // did not turn.
        let truth = Isometry3::rotation(Vector3::z() * 12.4f64.to_radians());
        let seen: Vec<SurfaceSample> = world
            .iter()
            .map(|s| SurfaceSample {
                point: truth.inverse() * s.point,
                normal: truth.inverse().rotation * s.normal,
            })
            .collect();
        let up = Vector3::z_axis();
        let found =
            search_heading_by_points(&seen, nearest, &Isometry3::identity(), &up, 0.5, 0.05, 20.0);
        // Found between the steps.
        let found = found.expect("a turn");
        assert!((found - 12.4).abs() < 0.2, "{found}");
        // Where the prediction is right, it stays.
        assert_eq!(
            search_heading_by_points(&seen, nearest, &truth, &up, 0.5, 0.05, 20.0),
            None
        );
        // A handful of samples is no evidence: the prediction stays.
        assert_eq!(
            search_heading_by_points(
                &seen[..10],
                nearest,
                &Isometry3::identity(),
                &up,
                0.5,
                0.05,
                20.0
            ),
            None
        );
    }

    #[test]
    fn candidates_alternate_outwards_and_stop_at_the_limit() {
        let p = RecoveryParams {
            max_yaw_deg: 25.0,
            yaw_step_deg: 10.0,
            ..Default::default()
        };
        assert_eq!(yaw_candidates(&p), vec![10.0, -10.0, 20.0, -20.0]);
        let off = RecoveryParams {
            yaw_step_deg: 0.0,
            ..Default::default()
        };
        assert!(yaw_candidates(&off).is_empty());
    }
}
