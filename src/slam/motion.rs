//! The motion model: where the sensor is expected to be next.
//!
//! The prediction starts frame-to-frame matching, supplies the pose in
//! directions the planes do not constrain (a corridor's axis), and is the
//! whole answer when registration fails.
//!
//! Because unobservable directions are extrapolated with the velocity, one
//! bad registration in an observable frame would otherwise set a wrong
//! velocity that the following degenerate frames repeat indefinitely (in a
//! corridor: a sensor driving backwards). The velocity estimate therefore
//! changes by at most `max_velocity_change` metres and
//! `max_rotation_change_deg` degrees per frame (a bounded acceleration:
//! 0.02 m per frame is 2 m/s² at 10 Hz).

use nalgebra::{Isometry3, Vector6};
use serde::{Deserialize, Serialize};

use crate::geometry::se3;

/// Motion models selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionModelName {
    /// The last relative motion repeats.
    ConstantVelocity,
    /// The sensor is expected where it was (the paper's frame-to-frame
    /// matching assumes small motion).
    Stationary,
}

/// Motion-model settings (`[slam.motion]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotionParams {
    /// The model.
    pub model: MotionModelName,
    /// Largest change of the velocity's translation per frame, m (∞ for
    /// the plain constant-velocity model).
    pub max_velocity_change: f64,
    /// Largest change of the velocity's rotation per frame, degrees.
    pub max_rotation_change_deg: f64,
}

impl Default for MotionParams {
    fn default() -> Self {
        Self {
            model: MotionModelName::ConstantVelocity,
            max_velocity_change: 0.02,
            max_rotation_change_deg: 1.0,
        }
    }
}

/// Predicts the next pose from the poses so far.
#[derive(Debug, Clone)]
pub struct MotionModel {
    params: MotionParams,
    last: Option<Isometry3<f64>>,
    velocity: Isometry3<f64>,
    has_velocity: bool,
}

impl MotionModel {
    /// A model with the given settings, with no pose yet.
    pub fn new(params: MotionParams) -> Self {
        Self {
            params,
            last: None,
            velocity: Isometry3::identity(),
            has_velocity: false,
        }
    }

    /// The predicted next pose (`T_world_sensor`); `None` before the first
    /// pose.
    pub fn predict(&self) -> Option<Isometry3<f64>> {
        let last = self.last?;
        Some(match self.params.model {
            MotionModelName::ConstantVelocity => last * self.velocity,
            MotionModelName::Stationary => last,
        })
    }

    /// The relative motion the model expects from the last pose to the
    /// next (identity before two poses or for the stationary model).
    pub fn velocity(&self) -> Isometry3<f64> {
        match self.params.model {
            MotionModelName::ConstantVelocity => self.velocity,
            MotionModelName::Stationary => Isometry3::identity(),
        }
    }

    /// Replace the last recorded pose (a back-end moved it), keeping the
    /// velocity.
    pub fn correct(&mut self, pose: Isometry3<f64>) {
        if self.last.is_some() {
            self.last = Some(pose);
        }
    }

    /// Record the pose of the frame just tracked. The first measured
    /// relative motion is taken as is; later ones move the velocity by at
    /// most the configured change.
    pub fn update(&mut self, pose: Isometry3<f64>) {
        if let Some(last) = self.last {
            let measured = last.inverse() * pose;
            if self.has_velocity {
                let mut delta = se3::local(&self.velocity, &measured);
                clamp_norm(&mut delta, 0, self.params.max_velocity_change);
                clamp_norm(
                    &mut delta,
                    3,
                    self.params.max_rotation_change_deg.to_radians(),
                );
                self.velocity = se3::retract(&self.velocity, &delta);
            } else {
                self.velocity = measured;
                self.has_velocity = true;
            }
        }
        self.last = Some(pose);
    }
}

/// Scale the 3-vector at `start` of `v` down to norm `max` if longer.
fn clamp_norm(v: &mut Vector6<f64>, start: usize, max: f64) {
    let n = v.fixed_rows::<3>(start).norm();
    if n > max && n > 0.0 {
        let scale = max.max(0.0) / n;
        v.fixed_rows_mut::<3>(start).scale_mut(scale);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn constant_velocity_repeats_the_last_motion_in_the_body_frame() {
        let mut m = MotionModel::new(MotionParams {
            max_velocity_change: f64::INFINITY,
            max_rotation_change_deg: f64::INFINITY,
            ..Default::default()
        });
        assert!(m.predict().is_none());
        let step = Isometry3::new(Vector3::new(0.1, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.1));
        let p0 = Isometry3::new(Vector3::new(1.0, 2.0, 0.0), Vector3::new(0.0, 0.0, 0.5));
        m.update(p0);
        assert_eq!(m.predict(), Some(p0));
        m.update(p0 * step);
        let expect = p0 * step * step;
        let got = m.predict().unwrap();
        assert!((got.translation.vector - expect.translation.vector).norm() < 1e-12);
        assert!(got.rotation.angle_to(&expect.rotation) < 1e-12);
        let mut s = MotionModel::new(MotionParams {
            model: MotionModelName::Stationary,
            ..Default::default()
        });
        s.update(p0);
        s.update(p0 * step);
        assert_eq!(s.predict(), Some(p0 * step));
    }

    #[test]
    fn one_bad_pose_moves_the_velocity_by_a_bounded_step() {
        let mut m = MotionModel::new(MotionParams::default());
        let step = Isometry3::translation(0.08, 0.0, 0.0);
        let mut pose = Isometry3::identity();
        for _ in 0..3 {
            m.update(pose);
            pose *= step;
        }
        // A registration puts the sensor 0.2 m back instead of 0.08 ahead.
        let last = pose * step.inverse();
        m.update(last * Isometry3::translation(-0.2, 0.0, 0.0));
        let v = m.velocity().translation.vector.x;
        assert!((v - 0.06).abs() < 1e-9, "{v}");
    }
}
