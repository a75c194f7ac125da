//! The motion model: where the sensor is expected to be next.
//!
//! The prediction starts frame-to-frame matching, supplies the pose in
//! directions the planes do not constrain (a corridor's axis), and is the
//! whole answer when registration fails.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

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

/// Predicts the next pose from the poses so far.
#[derive(Debug, Clone)]
pub struct MotionModel {
    kind: MotionModelName,
    last: Option<Isometry3<f64>>,
    velocity: Isometry3<f64>,
}

impl MotionModel {
    /// A model of the given kind, with no pose yet.
    pub fn new(kind: MotionModelName) -> Self {
        Self {
            kind,
            last: None,
            velocity: Isometry3::identity(),
        }
    }

    /// The predicted next pose (`T_world_sensor`); `None` before the first
    /// pose.
    pub fn predict(&self) -> Option<Isometry3<f64>> {
        let last = self.last?;
        Some(match self.kind {
            MotionModelName::ConstantVelocity => last * self.velocity,
            MotionModelName::Stationary => last,
        })
    }

    /// The relative motion the model expects from the last pose to the
    /// next (identity before two poses or for the stationary model).
    pub fn velocity(&self) -> Isometry3<f64> {
        match self.kind {
            MotionModelName::ConstantVelocity => self.velocity,
            MotionModelName::Stationary => Isometry3::identity(),
        }
    }

    /// Record the pose of the frame just tracked.
    pub fn update(&mut self, pose: Isometry3<f64>) {
        if let Some(last) = self.last {
            self.velocity = last.inverse() * pose;
        }
        self.last = Some(pose);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn constant_velocity_repeats_the_last_motion_in_the_body_frame() {
        let mut m = MotionModel::new(MotionModelName::ConstantVelocity);
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
        let mut s = MotionModel::new(MotionModelName::Stationary);
        s.update(p0);
        s.update(p0 * step);
        assert_eq!(s.predict(), Some(p0 * step));
    }
}
