//! Deskewing: a sweep's points moved to the frame's reference instant.
//!
//! A sensor that moves during its sweep measures each point from the pose
//! of that point's firing time, in the sensor frame of that time
//! ([`Point::time`]: seconds after the frame's stamp). Taken as one rigid
//! scan, the points are smeared: 0.1 s at 1 m/s moves the last column
//! 10 cm from the first, and a 45 deg/s turn displaces a wall 10 m away by
//! 0.8 m. Deskewing moves every point into the sensor frame at the frame's
//! stamp (the reference instant, time 0, [`crate::sim::Simulator`]'s and
//! Ouster's sweep start) with a motion estimate, as KISS-ICP does
//! (`Preprocessing.cpp`: constant velocity over the sweep, the relative
//! motion interpolated on SE(3) by the point's time).
//!
//! With `ξ` the body-frame twist per second (`(ρ, φ)`, as
//! [`MotionModel::velocity`](super::MotionModel::velocity)), the pose at
//! time `t` is `T(t) = T(0) · exp(t ξ)`, so a point `p` measured in the
//! sensor frame at `t` lies at `exp(t ξ) · p` in the frame at the stamp.
//! KISS-ICP normalises the times to `[0, 1]` and deskews to the scan's
//! end; here times are seconds and the reference is the stamp, so frames
//! at any rate and with any time origin (negative times too) deskew alike.
//!
//! Frames whose points all have time 0 (3DRef PLY frames, instantaneous
//! simulations) are left untouched, bit for bit.

use nalgebra::{Isometry3, Point3, Vector6};

use crate::cloud::{Frame, Point};
use crate::geometry::se3;

/// Whether any point of the frame carries a per-point time (non-zero):
/// the frames deskewing applies to.
pub fn is_timed(frame: &Frame) -> bool {
    frame.points.iter().any(|p| p.time != 0.0)
}

/// The transform that takes a point measured `time` seconds after the
/// stamp (in the sensor frame of that instant) into the sensor frame at
/// the stamp, for a body-frame twist per second `velocity`: `exp(time ·
/// velocity)`.
pub fn correction(velocity: &Vector6<f64>, time: f64) -> Isometry3<f64> {
    se3::exp(&(velocity * time))
}

/// Move every point of `frame` to the sensor frame at its stamp for the
/// body-frame twist per second `velocity` ([`correction`] by each point's
/// time). Times are kept (they say when the point was measured). Returns
/// whether anything moved: nothing does when every time is 0 or the
/// velocity is zero. Points of one firing time (a column, a pulse) share
/// one transform; nothing is allocated.
pub fn deskew_frame(frame: &mut Frame, velocity: &Vector6<f64>) -> bool {
    if !is_timed(frame) || velocity.iter().all(|v| *v == 0.0) {
        return false;
    }
    let mut at = f32::NAN;
    let mut transform = Isometry3::identity();
    for p in frame.points.iter_mut() {
        if p.time == 0.0 {
            continue;
        }
        if p.time != at {
            at = p.time;
            transform = correction(velocity, p.time as f64);
        }
        deskew_point(p, &transform);
    }
    true
}

/// A copy of `frame` deskewed for `velocity` ([`deskew_frame`]).
pub fn deskewed(frame: &Frame, velocity: &Vector6<f64>) -> Frame {
    let mut out = frame.clone();
    deskew_frame(&mut out, velocity);
    out
}

#[inline]
fn deskew_point(p: &mut Point, transform: &Isometry3<f64>) {
    let q = transform * Point3::from(p.position().coords);
    p.xyz = [q.x as f32, q.y as f32, q.z as f32];
}

/// The body-frame twist per second of frame `k` of a sequence with poses
/// `poses` (`T_world_sensor` at each frame's stamp) and stamps `stamps`:
/// the motion from frame `k` to frame `k + 1` over their interval (the
/// sweep of frame `k` runs from its stamp towards the next), or from
/// `k - 1` to `k` for the last frame. Zero when there is no neighbour or
/// the interval is not positive and finite.
pub fn velocity_from_poses(poses: &[Isometry3<f64>], stamps: &[f64], k: usize) -> Vector6<f64> {
    let n = poses.len().min(stamps.len());
    let (a, b) = match k {
        _ if k + 1 < n => (k, k + 1),
        _ if k > 0 && k < n => (k - 1, k),
        _ => return Vector6::zeros(),
    };
    let dt = stamps[b] - stamps[a];
    if !(dt > 0.0 && dt.is_finite()) {
        return Vector6::zeros();
    }
    se3::local(&poses[a], &poses[b]) / dt
}

/// The body-frame twist per second over the sweep of every frame of a
/// sequence with poses `poses` and stamps `stamps`, from poses that are
/// estimates (tracking's): the mean of the motions between consecutive
/// frames ([`velocity_from_poses`]) over the `half_window` intervals
/// before and after the frame's own (from its pose to the next), fewer at
/// the sequence's ends. A tracked pose is off by millimetres and tenths of
/// a degree, so one interval's motion is not the velocity; the mean over
/// an odd window centred on the sweep is, to first order, also where the
/// sensor turns (the turn of the intervals before and after cancels). 0:
/// each frame's own interval alone.
pub fn smoothed_velocities(
    poses: &[Isometry3<f64>],
    stamps: &[f64],
    half_window: usize,
) -> Vec<Vector6<f64>> {
    let n = poses.len().min(stamps.len());
    (0..n)
        .map(|k| smoothed_velocity(poses, stamps, k, half_window))
        .collect()
}

/// [`smoothed_velocities`] of frame `k` alone.
pub fn smoothed_velocity(
    poses: &[Isometry3<f64>],
    stamps: &[f64],
    k: usize,
    half_window: usize,
) -> Vector6<f64> {
    let n = poses.len().min(stamps.len());
    if n < 2 || k >= n {
        return Vector6::zeros();
    }
    // The intervals j (frame j to j + 1) around frame k's own.
    let own = k.min(n - 2);
    let lo = own.saturating_sub(half_window);
    let hi = (own + half_window).min(n - 2);
    let sum: Vector6<f64> = (lo..=hi)
        .map(|j| velocity_from_poses(poses, stamps, j))
        .sum();
    sum / (hi - lo + 1) as f64
}

/// The frames [`smoothed_velocity`] reads for frame `k` of a sequence of
/// `n` frames: the same velocity comes from these poses and stamps alone
/// (with `k` counted from the range's start), so a reader that hands out
/// one frame at a time need not gather a long sequence's stamps.
pub fn velocity_window(n: usize, k: usize, half_window: usize) -> std::ops::Range<usize> {
    let own = k.min(n.saturating_sub(2));
    let start = own.saturating_sub(half_window).min(k);
    start..(own + half_window + 2).min(n).max(start)
}

/// Intervals before and after a frame's own over which its deskewing
/// velocity averages the motion of estimated poses
/// ([`smoothed_velocities`]; the SLAM's second tracking pass, and every
/// pass over a sequence with poses). Tracked poses jitter by millimetres:
/// on the built-in `demo` walked at 1 m/s turning at 45 deg/s, one
/// interval's motion (0) left an ATE of 14 mm, the mean over 3 intervals
/// (1) 6.2 mm, over 5 (2) 6.0 mm, over 7 (3) 11 mm; a third tracking pass
/// made all but the last worse. Not a setting: a property of the
/// estimate's noise.
pub const VELOCITY_HALF_WINDOW: usize = 2;

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proptest::prelude::*;

    fn twist() -> impl Strategy<Value = Vector6<f64>> {
        (
            proptest::array::uniform3(-2.0f64..2.0),
            proptest::array::uniform3(-1.5f64..1.5),
        )
            .prop_map(|(r, w)| Vector6::new(r[0], r[1], r[2], w[0], w[1], w[2]))
    }

    proptest! {
        /// A world point seen at time `t` from the pose the constant
        /// velocity gives (`T0 · exp(t ξ)`), deskewed, is where the
        /// reference pose `T0` sees it.
        #[test]
        fn a_deskewed_point_is_seen_from_the_reference_pose(
            xi in twist(),
            t in -0.1f64..0.2,
            world in proptest::array::uniform3(-20.0f64..20.0),
            origin in proptest::array::uniform3(-5.0f64..5.0),
            yaw in -3.0f64..3.0,
        ) {
            let t0 = Isometry3::new(Vector3::from(origin), Vector3::new(0.1, -0.2, yaw));
            let at_t = t0 * se3::exp(&(xi * t));
            let world = Point3::from(world);
            let measured = at_t.inverse() * world;
            let deskewed = correction(&xi, t) * measured;
            let want = t0.inverse() * world;
            prop_assert!((deskewed - want).norm() < 1e-9, "{} vs {}", deskewed, want);
        }

        /// Zero velocity or time 0 change nothing, bit for bit.
        #[test]
        fn zero_velocity_or_time_is_the_identity(xi in twist(), x in -30.0f32..30.0, t in 0.001f32..0.1) {
            let point = |time: f32| Point { xyz: [x, 1.5, -0.25], time, ret: 1, ..Default::default() };
            let mut f = Frame { points: vec![point(0.0), point(t)], ..Default::default() };
            let before = f.points.clone();
            prop_assert!(!deskew_frame(&mut f, &Vector6::zeros()));
            prop_assert_eq!(&f.points, &before);
            let mut untimed = Frame { points: vec![point(0.0); 3], ..Default::default() };
            prop_assert!(!deskew_frame(&mut untimed, &xi));
            prop_assert_eq!(&untimed.points, &vec![point(0.0); 3]);
            // A timed frame keeps its time-0 points where they are.
            deskew_frame(&mut f, &xi);
            prop_assert_eq!(f.points[0], before[0]);
        }

        /// The velocity from the frames of [`velocity_window`] alone is the
        /// velocity from the whole sequence, bit for bit.
        #[test]
        fn the_window_holds_every_frame_the_velocity_reads(
            steps in proptest::collection::vec((twist(), 0.05f64..0.2), 0..12),
            k in 0usize..14,
            half in 0usize..4,
        ) {
            let (mut poses, mut stamps) = (vec![Isometry3::identity()], vec![5.0]);
            for (xi, dt) in &steps {
                poses.push(poses[poses.len() - 1] * se3::exp(&(xi * *dt)));
                stamps.push(stamps[stamps.len() - 1] + dt);
            }
            let whole = smoothed_velocity(&poses, &stamps, k, half);
            let w = velocity_window(poses.len(), k, half);
            let windowed = smoothed_velocity(&poses[w.clone()], &stamps[w.clone()], k - w.start, half);
            prop_assert_eq!(whole, windowed);
        }

        /// The velocity from two poses reproduces the second from the
        /// first over their interval.
        #[test]
        fn velocity_from_poses_spans_the_interval(xi in twist(), dt in 0.05f64..0.2) {
            let a = Isometry3::new(Vector3::new(1.0, 2.0, 0.5), Vector3::new(0.0, 0.0, 0.7));
            let b = a * se3::exp(&(xi * dt));
            let poses = [a, b];
            let stamps = [10.0, 10.0 + dt];
            for k in 0..2 {
                let v = velocity_from_poses(&poses, &stamps, k);
                let moved = a * correction(&v, dt);
                prop_assert!((moved.translation.vector - b.translation.vector).norm() < 1e-9);
                prop_assert!(moved.rotation.angle_to(&b.rotation) < 1e-9);
            }
        }
    }

    #[test]
    fn no_neighbour_or_bad_interval_gives_zero_velocity() {
        let p = [Isometry3::identity(), Isometry3::translation(1.0, 0.0, 0.0)];
        assert_eq!(velocity_from_poses(&p[..1], &[0.0], 0), Vector6::zeros());
        assert_eq!(velocity_from_poses(&p, &[1.0, 1.0], 0), Vector6::zeros());
        assert_eq!(velocity_from_poses(&p, &[0.0, 0.1], 5), Vector6::zeros());
    }
}
