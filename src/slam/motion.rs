//! The motion model: where the sensor is expected to be next.
//!
//! The prediction starts frame-to-frame matching, supplies the pose in
//! directions the planes do not constrain (a corridor's axis), and is the
//! whole answer when registration fails.
//!
//! The velocity is a twist per second, and a prediction extrapolates it
//! over the time that really elapsed since the last frame (the frames'
//! timestamps): at 5 Hz the sensor moves twice as far between frames as at
//! 10 Hz, and after a 0.5 s gap six times as far. A velocity per frame
//! would put the sensor one frame's motion ahead whatever the interval, and
//! the free directions of a corridor keep that error.
//!
//! Because unobservable directions are extrapolated with the velocity, one
//! bad registration in an observable frame would otherwise set a wrong
//! velocity that the following degenerate frames repeat indefinitely (in a
//! corridor: a sensor driving backwards). The velocity estimate therefore
//! changes by at most `max_acceleration` × the interval (m/s) and
//! `max_angular_acceleration_deg` × the interval (deg/s) per frame: a
//! bounded acceleration.
//!
//! In the directions a frame's planes left free, its pose is the
//! prediction moved by whatever the points measured, a far noisier
//! measurement (a corridor's axis from door frames and mullions). There the
//! velocity follows the measured motion only by `free_direction_gain` per
//! frame, a low-pass over the frames of the degenerate stretch: one
//! point registration that is 2 cm off would otherwise add 2 cm to every
//! following frame of the corridor (on the glass-lined loop with range-noise
//! seed 2, tracking was 0.24 m off at its end with gain 1, 0.06 m with 0.25).
//!
//! A tracked pose is *implausible* ([`MotionUpdate::implausible`]) when it
//! lies farther from the constant-velocity extrapolation of the two
//! tracked poses before it than `implausible_jump` (m) or
//! `implausible_turn_deg` plus what the bounded acceleration allows over
//! the interval (`a dt² / 2`). The bounded velocity itself is no measure:
//! it lags a real sharp turn by design, and registration noise over a
//! 0.1 s interval looks like metres per second squared. The tracker
//! reports implausible frames; they are the signature of a wrong
//! registration (a jump) or of an input whose frames do not follow each
//! other.

use nalgebra::{Isometry3, Vector6};
use serde::{Deserialize, Serialize};

use crate::geometry::se3;

/// Motion models selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionModelName {
    /// The last velocity (a twist per second) goes on over the elapsed
    /// time.
    ConstantVelocity,
    /// The sensor is expected where it was (the paper's frame-to-frame
    /// matching assumes small motion).
    Stationary,
}

/// Motion-model settings (`[slam.motion]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionParams {
    /// The model.
    pub model: MotionModelName,
    /// Largest linear acceleration the velocity estimate follows, m/s²
    /// (∞ for the plain constant-velocity model): per frame its
    /// translation changes by at most this times the interval.
    pub max_acceleration: f64,
    /// Largest angular acceleration the velocity estimate follows, deg/s².
    pub max_angular_acceleration_deg: f64,
    /// Interval assumed between frames whose timestamps do not give one
    /// (missing, equal or decreasing), s.
    pub frame_period: f64,
    /// A tracked pose farther than this (plus `max_acceleration dt² / 2`)
    /// from the extrapolation of the poses before it is implausible (it is
    /// reported), m: [`IMPLAUSIBLE_JUMP`].
    #[serde(skip, default = "implausible_jump")]
    pub implausible_jump: f64,
    /// ... or turned farther than this (plus `max_angular_acceleration_deg
    /// dt² / 2`), degrees: [`IMPLAUSIBLE_TURN_DEG`].
    #[serde(skip, default = "implausible_turn_deg")]
    pub implausible_turn_deg: f64,
    /// Share of the measured change of velocity taken per frame in the
    /// directions the frame's planes left free (1: as in the observed
    /// ones; the bounded acceleration applies after it).
    pub free_direction_gain: f64,
}

/// A tracked pose farther than this, m, from the extrapolation of the two
/// before it (plus `max_acceleration dt² / 2`) is reported implausible.
pub const IMPLAUSIBLE_JUMP: f64 = 0.15;

/// ... or turned farther than this, degrees (plus
/// `max_angular_acceleration_deg dt² / 2`).
pub const IMPLAUSIBLE_TURN_DEG: f64 = 10.0;

fn implausible_jump() -> f64 {
    IMPLAUSIBLE_JUMP
}

fn implausible_turn_deg() -> f64 {
    IMPLAUSIBLE_TURN_DEG
}

impl Default for MotionParams {
    /// `[slam.motion]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.motion")
    }
}

/// What one [`MotionModel::update`] found: how far the tracked pose is
/// from the constant-velocity extrapolation of the two tracked poses
/// before it (0 before there are two).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotionUpdate {
    /// Distance of the position from the extrapolation, m.
    pub jump: f64,
    /// Angle of the orientation from the extrapolation, degrees.
    pub turn_deg: f64,
    /// Whether either is beyond its bound (`implausible_jump`,
    /// `implausible_turn_deg`, each plus the bounded acceleration over the
    /// interval): a wrong registration or frames that do not follow each
    /// other.
    pub implausible: bool,
}

/// Predicts the next pose from the poses so far and their times.
#[derive(Debug, Clone)]
pub struct MotionModel {
    params: MotionParams,
    last: Option<Isometry3<f64>>,
    /// Body-frame twist per second `(ρ, φ)`, of bounded change.
    velocity: Vector6<f64>,
    has_velocity: bool,
    /// The last measured twist per second, unbounded (for the
    /// plausibility check).
    measured: Vector6<f64>,
}

impl MotionModel {
    /// A model with the given settings, with no pose yet.
    pub fn new(params: MotionParams) -> Self {
        Self {
            params,
            last: None,
            velocity: Vector6::zeros(),
            has_velocity: false,
            measured: Vector6::zeros(),
        }
    }

    /// The interval to use for `dt` (seconds): itself when positive and
    /// finite, else the configured frame period.
    pub fn interval(&self, dt: Option<f64>) -> f64 {
        match dt {
            Some(dt) if dt.is_finite() && dt > 0.0 => dt,
            _ => self.params.frame_period,
        }
    }

    /// The predicted pose (`T_world_sensor`) `dt` seconds after the last
    /// one; `None` before the first pose.
    pub fn predict(&self, dt: f64) -> Option<Isometry3<f64>> {
        let last = self.last?;
        Some(last * self.motion_over(dt))
    }

    /// The relative motion the model expects over `dt` seconds from the
    /// last pose (identity before two poses or for the stationary model).
    pub fn motion_over(&self, dt: f64) -> Isometry3<f64> {
        match self.params.model {
            MotionModelName::ConstantVelocity => se3::exp(&(self.velocity * dt)),
            MotionModelName::Stationary => Isometry3::identity(),
        }
    }

    /// The velocity, a body-frame twist per second `(ρ, φ)` (zero for the
    /// stationary model).
    pub fn velocity(&self) -> Vector6<f64> {
        match self.params.model {
            MotionModelName::ConstantVelocity => self.velocity,
            MotionModelName::Stationary => Vector6::zeros(),
        }
    }

    /// Replace the last recorded pose (a back-end moved it), keeping the
    /// velocity.
    pub fn correct(&mut self, pose: Isometry3<f64>) {
        if self.last.is_some() {
            self.last = Some(pose);
        }
    }

    /// Record the pose of the frame just tracked, `dt` seconds after the
    /// last one (one `frame_period` when not positive). The first measured
    /// velocity is taken as is; later ones move the velocity by at most
    /// the bounded acceleration over `dt`. The returned [`MotionUpdate`]
    /// says how far the pose is from the extrapolation of the poses before
    /// it.
    pub fn update(&mut self, pose: Isometry3<f64>, dt: f64) -> MotionUpdate {
        self.update_with_free(pose, dt, &[])
    }

    /// [`MotionModel::update`] for a pose whose registration left the
    /// orthonormal body-frame directions `free` (tangent vectors `(ρ, φ)`)
    /// unobserved by its planes: along them the velocity takes only
    /// `free_direction_gain` of the measured change.
    pub fn update_with_free(
        &mut self,
        pose: Isometry3<f64>,
        dt: f64,
        free: &[Vector6<f64>],
    ) -> MotionUpdate {
        let mut out = MotionUpdate::default();
        let p = &self.params;
        if let Some(last) = self.last {
            let dt = self.interval(Some(dt));
            let measured = se3::local(&last, &pose) / dt;
            if self.has_velocity {
                let expected = last * se3::exp(&(self.measured * dt));
                out.jump = (pose.translation.vector - expected.translation.vector).norm();
                out.turn_deg = pose.rotation.angle_to(&expected.rotation).to_degrees();
                let allowance = 0.5 * dt * dt;
                out.implausible = out.jump > p.implausible_jump + p.max_acceleration * allowance
                    || out.turn_deg
                        > p.implausible_turn_deg + p.max_angular_acceleration_deg * allowance;
                let mut delta = measured - self.velocity;
                let gain = p.free_direction_gain;
                if gain < 1.0 {
                    for d in free {
                        let along = d.dot(&delta);
                        delta -= d * (along * (1.0 - gain));
                    }
                }
                clamp_norm(&mut delta, 0, p.max_acceleration * dt);
                clamp_norm(
                    &mut delta,
                    3,
                    p.max_angular_acceleration_deg.to_radians() * dt,
                );
                self.velocity += delta;
            } else {
                self.velocity = measured;
                self.has_velocity = true;
            }
            self.measured = measured;
        }
        self.last = Some(pose);
        out
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

    fn unbounded() -> MotionParams {
        MotionParams {
            max_acceleration: f64::INFINITY,
            max_angular_acceleration_deg: f64::INFINITY,
            ..Default::default()
        }
    }

    fn close(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
        (a.translation.vector - b.translation.vector).norm() < 1e-9
            && a.rotation.angle_to(&b.rotation) < 1e-9
    }

    #[test]
    fn constant_velocity_repeats_the_last_motion_in_the_body_frame() {
        let mut m = MotionModel::new(unbounded());
        assert!(m.predict(0.1).is_none());
        let step = Isometry3::new(Vector3::new(0.1, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.1));
        let p0 = Isometry3::new(Vector3::new(1.0, 2.0, 0.0), Vector3::new(0.0, 0.0, 0.5));
        m.update(p0, 0.1);
        assert_eq!(m.predict(0.1), Some(p0));
        m.update(p0 * step, 0.1);
        assert!(close(&m.predict(0.1).unwrap(), &(p0 * step * step)));
        let mut s = MotionModel::new(MotionParams {
            model: MotionModelName::Stationary,
            ..Default::default()
        });
        s.update(p0, 0.1);
        s.update(p0 * step, 0.1);
        assert_eq!(s.predict(0.1), Some(p0 * step));
    }

    #[test]
    fn a_prediction_extrapolates_over_the_elapsed_time() {
        // 0.1 m and 0.1 rad per 0.1 s; after a 0.6 s interval the model
        // expects six steps, after 0.2 s two.
        let mut m = MotionModel::new(MotionParams::default());
        let step = Isometry3::new(Vector3::new(0.1, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.1));
        let p0 = Isometry3::identity();
        m.update(p0, 0.1);
        m.update(step, 0.1);
        let six = (0..6).fold(step, |p, _| p * step);
        assert!(close(&m.predict(0.6).unwrap(), &six));
        assert!(close(&m.predict(0.2).unwrap(), &(step * step * step)));
        // The same motion at 5 Hz: 0.2 m per 0.2 s is the same velocity.
        let mut slow = MotionModel::new(MotionParams::default());
        slow.update(p0, 0.2);
        slow.update(step * step, 0.2);
        assert!((slow.velocity() - m.velocity()).norm() < 1e-9);
        // A frame without a usable interval counts one frame period.
        assert_eq!(m.interval(None), 0.1);
        assert_eq!(m.interval(Some(0.0)), 0.1);
        assert_eq!(m.interval(Some(-0.3)), 0.1);
        assert_eq!(m.interval(Some(0.25)), 0.25);
    }

    #[test]
    fn along_a_free_direction_the_velocity_takes_only_its_gain_of_a_change() {
        // Driving along x at 0.8 m/s; then a frame whose planes left x free
        // is registered 2 cm further along x and 1 cm along y (observed).
        let params = MotionParams {
            max_acceleration: f64::INFINITY,
            free_direction_gain: 0.25,
            ..Default::default()
        };
        let step = Isometry3::translation(0.08, 0.0, 0.0);
        let mut m = MotionModel::new(params);
        let mut pose = Isometry3::identity();
        for _ in 0..3 {
            m.update(pose, 0.1);
            pose *= step;
        }
        let last = pose * step.inverse();
        let x = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        m.update_with_free(last * Isometry3::translation(0.1, 0.01, 0.0), 0.1, &[x]);
        let v = m.velocity();
        // x: 0.8 + 0.25 * 0.2 m/s; y: the whole 0.1 m/s.
        assert!((v[0] - 0.85).abs() < 1e-9, "{v}");
        assert!((v[1] - 0.1).abs() < 1e-9, "{v}");
        // Gain 1 (and no free direction) is the plain update.
        let mut plain = MotionModel::new(MotionParams {
            free_direction_gain: 1.0,
            ..params
        });
        let mut pose = Isometry3::identity();
        for _ in 0..3 {
            plain.update(pose, 0.1);
            pose *= step;
        }
        plain.update_with_free(last * Isometry3::translation(0.1, 0.01, 0.0), 0.1, &[x]);
        assert!((plain.velocity()[0] - 1.0).abs() < 1e-9);
    }

    #[test]
    fn one_bad_pose_moves_the_velocity_by_a_bounded_step_and_is_implausible() {
        let mut m = MotionModel::new(MotionParams::default());
        let step = Isometry3::translation(0.08, 0.0, 0.0);
        let mut pose = Isometry3::identity();
        for _ in 0..3 {
            assert!(!m.update(pose, 0.1).implausible);
            pose *= step;
        }
        // A registration puts the sensor 0.2 m back instead of 0.08 ahead:
        // 0.28 m from the extrapolation, and the velocity (0.8 m/s) follows
        // 2 m/s² of the 28 m/s² it would take.
        let last = pose * step.inverse();
        let u = m.update(last * Isometry3::translation(-0.2, 0.0, 0.0), 0.1);
        assert!(u.implausible);
        assert!((u.jump - 0.28).abs() < 1e-9, "{u:?}");
        let v = m.velocity()[0];
        assert!((v - 0.6).abs() < 1e-9, "{v}");
        // A 12 degree turn within 0.1 s after driving straight is
        // implausible, 5 degrees is not.
        let mut t = MotionModel::new(MotionParams::default());
        t.update(Isometry3::identity(), 0.1);
        t.update(step, 0.1);
        let turned = |deg: f64| step * step * Isometry3::rotation(Vector3::z() * deg.to_radians());
        assert!(!t.clone().update(turned(5.0), 0.1).implausible);
        let u = t.update(turned(12.0), 0.1);
        assert!(u.implausible && (u.turn_deg - 12.0).abs() < 1e-9, "{u:?}");
        // The bounds grow with the interval: over 0.6 s the velocity may
        // change by 1.2 m/s, and 0.3 m off the extrapolation is plausible
        // (0.15 + 2 × 0.6² / 2 = 0.51 m).
        let mut g = MotionModel::new(MotionParams::default());
        g.update(Isometry3::identity(), 0.1);
        g.update(Isometry3::translation(0.1, 0.0, 0.0), 0.1);
        let u = g.update(Isometry3::translation(0.1 + 0.6 * 1.5, 0.0, 0.0), 0.6);
        assert!(!u.implausible && (u.jump - 0.3).abs() < 1e-9, "{u:?}");
        assert!((g.velocity()[0] - 1.5).abs() < 1e-9);
    }
}
