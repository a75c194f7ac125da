//! The sensor's path: a polyline of waypoints driven at constant speed, with
//! a heading that follows the path direction, smoothed over a window so the
//! sensor turns gradually at corners.
//!
//! Time `t` maps to arc length `s = speed · t`. A closed path (`loop`) wraps
//! around; an open path is driven back and forth (the sensor turns around at
//! the ends), so any number of frames is defined. Poses are
//! `T_world_sensor`: the heading's yaw, then a fixed mounting tilt (roll
//! and pitch, zero by default: the sensor upright). A turn rate (zero by
//! default) adds a yaw growing at that rate with time on top of the
//! heading: a sensor that keeps turning while it walks (a hand-held
//! scanner swept round, a robot spinning), the motion that smears a sweep
//! most (issue 40: "walks at 1 m/s, turns at 45 deg/s").

use glam::DVec3;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Most straight pieces integrated for one smoothed heading.
const MAX_PIECES: usize = 10_000;

/// A validated trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    waypoints: Vec<DVec3>,
    /// Cumulative arc length at each waypoint (and, for loops, at the
    /// closing point after the last waypoint).
    cumulative: Vec<f64>,
    speed: f64,
    closed: bool,
    smoothing: f64,
    /// Fixed mounting rotation (roll about x, then pitch about y), applied
    /// in the sensor frame after the heading.
    tilt: UnitQuaternion<f64>,
    /// Yaw rate on top of the heading, rad/s.
    turn_rate: f64,
}

impl Trajectory {
    /// A trajectory through `waypoints` at `speed` m/s; `closed` returns to
    /// the first waypoint; `smoothing` is the half-width (metres of path) of
    /// the heading window. Fails when there are fewer than two distinct
    /// waypoints or the speed is not positive.
    pub fn new(
        waypoints: Vec<DVec3>,
        speed: f64,
        closed: bool,
        smoothing: f64,
    ) -> Result<Self, String> {
        if waypoints.len() < 2 {
            return Err("needs at least two waypoints".into());
        }
        let limit = super::surface::MAX_COORDINATE;
        if waypoints
            .iter()
            .any(|w| !w.is_finite() || w.abs().max_element() > limit)
        {
            return Err(format!(
                "waypoint coordinates must be finite and within ±{limit} m"
            ));
        }
        if !(speed > 0.0) || !speed.is_finite() || speed > 1e4 {
            return Err(format!("speed must be in (0, 1e4] m/s, got {speed}"));
        }
        if !(smoothing >= 0.0) || !(smoothing <= limit) {
            return Err(format!(
                "heading_smoothing must be non-negative, got {smoothing}"
            ));
        }
        let mut cumulative = vec![0.0];
        let n = waypoints.len();
        let segments = if closed { n } else { n - 1 };
        for i in 0..segments {
            let a = waypoints[i];
            let b = waypoints[(i + 1) % n];
            let len = (b - a).length();
            if !(len > 1e-6) {
                return Err(format!(
                    "waypoints {i} and {} coincide (consecutive waypoints must differ)",
                    (i + 1) % n
                ));
            }
            cumulative.push(cumulative[i] + len);
        }
        Ok(Self {
            waypoints,
            cumulative,
            speed,
            closed,
            smoothing,
            tilt: UnitQuaternion::identity(),
            turn_rate: 0.0,
        })
    }

    /// Path length, metres (one lap for a loop).
    pub fn length(&self) -> f64 {
        *self.cumulative.last().unwrap_or(&0.0)
    }

    /// Speed, m/s.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Whether the path is a loop.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The waypoints.
    pub fn waypoints(&self) -> &[DVec3] {
        &self.waypoints
    }

    /// Frames needed to drive the path once at `rate_hz` (one lap for a
    /// loop, start to end inclusive for an open path).
    pub fn default_frames(&self, rate_hz: f64) -> usize {
        let steps = (self.length() / self.speed * rate_hz).floor() as usize;
        if self.closed {
            steps.max(1)
        } else {
            steps + 1
        }
    }

    /// Map an unbounded arc length to a point of the path and the direction
    /// of travel there (+1 forward, -1 driving back on an open path).
    fn fold(&self, s: f64) -> (f64, f64) {
        let len = self.length();
        if self.closed {
            (s.rem_euclid(len), 1.0)
        } else {
            let m = s.rem_euclid(2.0 * len);
            if m <= len {
                (m, 1.0)
            } else {
                (2.0 * len - m, -1.0)
            }
        }
    }

    /// Segment index and fraction along it for a folded arc length.
    fn locate(&self, s: f64) -> (usize, f64) {
        let segs = self.cumulative.len() - 1;
        let i = self
            .cumulative
            .partition_point(|&c| c <= s)
            .saturating_sub(1)
            .min(segs - 1);
        let len = self.cumulative[i + 1] - self.cumulative[i];
        (i, ((s - self.cumulative[i]) / len).clamp(0.0, 1.0))
    }

    fn segment(&self, i: usize) -> (DVec3, DVec3) {
        let n = self.waypoints.len();
        (self.waypoints[i], self.waypoints[(i + 1) % n])
    }

    /// Position at unbounded arc length `s`.
    pub fn position(&self, s: f64) -> DVec3 {
        let (f, _) = self.fold(s);
        let (i, u) = self.locate(f);
        let (a, b) = self.segment(i);
        a + (b - a) * u
    }

    /// Unit horizontal direction of travel of segment `i` driven with
    /// `sign` (`None` on a vertical segment).
    fn direction(&self, i: usize, sign: f64) -> Option<DVec3> {
        let (a, b) = self.segment(i);
        let t = DVec3::new(b.x - a.x, b.y - a.y, 0.0) * sign;
        (t.length() > 1e-9).then(|| t.normalize())
    }

    /// The straight piece of motion starting at unbounded arc length `s`:
    /// its direction of travel and the path length until the next corner
    /// (or turn-around).
    fn piece(&self, s: f64) -> (Option<DVec3>, f64) {
        let (f, sign) = self.fold(s);
        let (mut i, _) = self.locate(f);
        let ahead = if sign > 0.0 {
            self.cumulative[i + 1] - f
        } else {
            if f - self.cumulative[i] <= 1e-12 && i > 0 {
                i -= 1;
            }
            f - self.cumulative[i]
        };
        (self.direction(i, sign), ahead)
    }

    /// Smoothed heading (yaw, radians) at unbounded arc length `s`: the
    /// direction of the Hann-weighted mean of the travel directions over
    /// `[s - w, s + w]`, integrated exactly piece by piece so the heading
    /// is a continuous function of `s`.
    pub fn heading(&self, s: f64) -> f64 {
        let w = self.smoothing;
        // Normalised cumulative Hann weight at x in [0, 1].
        let cumulative = |x: f64| x - (std::f64::consts::TAU * x).sin() / std::f64::consts::TAU;
        let mut sum = DVec3::ZERO;
        if w > 0.0 {
            let (lo, hi) = (s - w, s + w);
            let weight = |a: f64, b: f64| {
                cumulative((b - lo) / (hi - lo)) - cumulative((a - lo) / (hi - lo))
            };
            let mut a = lo;
            for _ in 0..MAX_PIECES {
                if a >= hi {
                    break;
                }
                let (dir, b) = if !self.closed && a < 0.0 {
                    // Before the start the sensor faces its first segment.
                    (self.direction(0, 1.0), hi.min(0.0))
                } else {
                    let (dir, ahead) = self.piece(a);
                    (dir, hi.min(a + ahead.max(1e-9)))
                };
                if let Some(d) = dir {
                    sum += d * weight(a, b);
                }
                a = b;
            }
        }
        if sum.length() < 1e-6 {
            sum = self
                .piece(s)
                .0
                .or_else(|| self.piece(s + 1e-3).0)
                .unwrap_or(DVec3::X);
        }
        sum.y.atan2(sum.x)
    }

    /// The same trajectory with the sensor mounted tilted by `[roll,
    /// pitch]` degrees (about its x then y axis; each within ±30).
    pub fn with_tilt_deg(mut self, tilt: [f64; 2]) -> Result<Self, String> {
        if !tilt.iter().all(|a| a.is_finite() && a.abs() <= 30.0) {
            return Err(format!("tilt_deg must be within ±30 degrees, got {tilt:?}"));
        }
        let [roll, pitch] = tilt.map(f64::to_radians);
        self.tilt = UnitQuaternion::from_euler_angles(roll, pitch, 0.0);
        Ok(self)
    }

    /// The same trajectory with the sensor turning about its vertical axis
    /// at `rate` deg/s on top of the path's heading (within ±720 deg/s;
    /// 0: the heading alone).
    pub fn with_turn_rate_deg(mut self, rate: f64) -> Result<Self, String> {
        if !(rate.is_finite() && rate.abs() <= 720.0) {
            return Err(format!(
                "turn_rate_deg must be within ±720 deg/s, got {rate}"
            ));
        }
        self.turn_rate = rate.to_radians();
        Ok(self)
    }

    /// The turn rate on top of the heading, rad/s.
    pub fn turn_rate(&self) -> f64 {
        self.turn_rate
    }

    /// `T_world_sensor` at time `t` seconds.
    pub fn pose(&self, t: f64) -> Isometry3<f64> {
        let s = self.speed * t;
        let p = self.position(s);
        let mut yaw = self.heading(s);
        if self.turn_rate != 0.0 {
            yaw += self.turn_rate * t;
        }
        Isometry3::from_parts(
            Translation3::new(p.x, p.y, p.z),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * self.tilt,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(closed: bool) -> Trajectory {
        Trajectory::new(
            vec![
                DVec3::new(0.0, 0.0, 1.0),
                DVec3::new(4.0, 0.0, 1.0),
                DVec3::new(4.0, 4.0, 1.0),
                DVec3::new(0.0, 4.0, 1.0),
            ],
            1.0,
            closed,
            0.5,
        )
        .unwrap()
    }

    #[test]
    fn lengths_and_frame_counts() {
        assert!((square(false).length() - 12.0).abs() < 1e-12);
        assert!((square(true).length() - 16.0).abs() < 1e-12);
        assert_eq!(square(false).default_frames(10.0), 121);
        assert_eq!(square(true).default_frames(10.0), 160);
    }

    #[test]
    fn heading_follows_the_path_and_turns_smoothly() {
        let t = square(true);
        assert!(t.heading(2.0).abs() < 1e-9);
        assert!((t.heading(6.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        // At the corner the heading is about half-way through the turn.
        let corner = t.heading(4.0).to_degrees();
        assert!((35.0..55.0).contains(&corner), "{corner}");
        // The turn is spread over the window: 90 deg over 1 m of path turns at
        // most ~11.5 deg per 5 cm (the Hann weight peaks mid-window).
        let mut last = t.heading(0.0);
        for k in 1..400 {
            let h = t.heading(k as f64 * 0.05);
            let mut dh = h - last;
            dh = (dh + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(dh.abs() < 12f64.to_radians(), "jump {dh} at {k}");
            last = h;
        }
    }

    #[test]
    fn open_paths_are_driven_back_and_loops_wrap() {
        let open = square(false);
        assert!((open.position(13.0) - DVec3::new(1.0, 4.0, 1.0)).length() < 1e-12);
        assert!((open.heading(14.0).abs() - 0.0).abs() < 1e-9); // driving back: +x
        let closed = square(true);
        assert!((closed.position(17.0) - DVec3::new(1.0, 0.0, 1.0)).length() < 1e-12);
    }

    #[test]
    fn a_turn_rate_adds_yaw_with_time() {
        let t = square(true).with_turn_rate_deg(45.0).unwrap();
        let (a, b) = (t.pose(1.5), t.pose(1.6));
        let turned = a.rotation.angle_to(&b.rotation).to_degrees();
        // On a straight piece the path's heading is constant.
        assert!((turned - 4.5).abs() < 1e-9, "{turned}");
        assert_eq!(
            square(true).pose(1.5),
            square(true).with_turn_rate_deg(0.0).unwrap().pose(1.5)
        );
        assert!(square(true).with_turn_rate_deg(f64::NAN).is_err());
    }

    #[test]
    fn bad_trajectories_are_rejected() {
        assert!(Trajectory::new(vec![DVec3::ZERO], 1.0, false, 0.0).is_err());
        assert!(Trajectory::new(vec![DVec3::ZERO, DVec3::ZERO], 1.0, false, 0.0).is_err());
        assert!(Trajectory::new(vec![DVec3::ZERO, DVec3::X], 0.0, false, 0.0).is_err());
    }
}
