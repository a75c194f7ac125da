//! The floor under a classified map, for the top view's height slice.
//!
//! `detect` has no ground landmark (its map holds the reflective planes
//! only), so the floor is found in the map itself: the near-horizontal plane
//! (within 20° of the world's xy plane, z up) holding the most Normal points
//! below the sensor. The floor is the largest horizontal surface below a
//! sensor carried through a room; walls are vertical; the ceiling is above
//! the sensor. A plane, not a height: the world frame of the shared real
//! frames is tilted about 6° against their floor, which rises 0.9 m across
//! the map, so a horizontal slice would cut through it. And not a low
//! percentile of the heights: those frames hold Normal points 3 m below
//! their floor (a stairwell or an atrium), which pull any percentile down.

use nalgebra::Point3;

use crate::classify::Class;
use crate::geometry::fit::fit_plane;
use crate::geometry::Plane;
use crate::io::MapPoint;
use crate::rng::SplitMix64;

/// Largest angle between the floor's normal and the world's z axis, degrees.
const MAX_TILT_DEG: f64 = 20.0;
/// A point this close to a candidate plane supports it, m.
const INLIER: f64 = 0.05;
/// Points scored per candidate (a regular subsample beyond).
const MAX_SCORED: usize = 20_000;
/// Candidate planes tried.
const ITERATIONS: usize = 300;

/// The floor under `points` (world frame, z up): a plane facing up
/// (`n.z > 0`), so its signed distance is the height above the floor.
/// `sensor_heights` are the sensor's z along its path (without them, the
/// median height of the Normal points stands for the sensor's). `None`
/// without a near-horizontal plane of at least 50 Normal points below the
/// sensor. Deterministic.
pub fn fit_floor(points: &[MapPoint], sensor_heights: &[f64]) -> Option<Plane> {
    let normal: Vec<Point3<f64>> = points
        .iter()
        .filter(|p| p.class == Class::Normal)
        .map(|p| Point3::new(p.xyz[0] as f64, p.xyz[1] as f64, p.xyz[2] as f64))
        .filter(|p| p.coords.iter().all(|v| v.is_finite()))
        .collect();
    let sensor = match median(sensor_heights.iter().copied()) {
        Some(z) => z,
        None => median(normal.iter().map(|p| p.z))?,
    };
    let below: Vec<Point3<f64>> = normal.into_iter().filter(|p| p.z < sensor).collect();
    let step = below.len().div_ceil(MAX_SCORED).max(1);
    let scored: Vec<Point3<f64>> = below.iter().step_by(step).copied().collect();
    if scored.len() < 50 {
        return None;
    }
    let cos_tilt = MAX_TILT_DEG.to_radians().cos();
    let support = |plane: &Plane| {
        scored
            .iter()
            .filter(|p| plane.signed_distance(p).abs() <= INLIER)
            .count()
    };
    let mut rng = SplitMix64::new(0xF100_5EED);
    let mut best: Option<(usize, Plane)> = None;
    for _ in 0..ITERATIONS {
        let [a, b, c] = [0; 3].map(|_| scored[rng.below(scored.len())]);
        let Some(plane) = Plane::from_point_normal(&a, &(b - a).cross(&(c - a))) else {
            continue;
        };
        if plane.normal.z.abs() < cos_tilt {
            continue;
        }
        let n = support(&plane);
        if best.as_ref().is_none_or(|(m, _)| n > *m) {
            best = Some((n, plane));
        }
    }
    let (n, plane) = best?;
    if n < 50 {
        return None;
    }
    // Refit to all its points below the sensor, facing up.
    let inliers = below
        .iter()
        .filter(|p| plane.signed_distance(p).abs() <= INLIER)
        .copied();
    let refit = fit_plane(inliers).map_or(plane, |(p, _)| p);
    let up = if refit.normal.z < 0.0 {
        refit.flipped()
    } else {
        refit
    };
    (up.normal.z >= cos_tilt).then_some(up)
}

/// The median of finite `values` (the upper one of an even count).
fn median(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|z| z.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64, z: f64, class: Class) -> MapPoint {
        MapPoint {
            xyz: [x as f32, y as f32, z as f32],
            class,
            mirrored: false,
            confidence: 1.0,
        }
    }

    /// A room whose floor rises 6° along x (a tilted world frame), with
    /// walls, a ceiling and a stairwell 3 m below the floor: the floor
    /// plane is found, not the stairwell and not a horizontal layer.
    #[test]
    fn the_floor_is_the_largest_near_horizontal_plane_below_the_sensor() {
        let slope = 6f64.to_radians().tan();
        let floor_z = |x: f64| -1.5 + slope * x;
        let mut pts = Vec::new();
        for i in 0..80 {
            for j in 0..40 {
                let (x, y) = (-4.0 + 0.1 * i as f64, -2.0 + 0.1 * j as f64);
                pts.push(point(x, y, floor_z(x), Class::Normal));
                pts.push(point(x, y, floor_z(x) + 3.0, Class::Normal));
            }
        }
        for k in 0..60 {
            for h in 0..30 {
                let (t, z) = (-4.0 + 0.13 * k as f64, 0.1 * h as f64);
                pts.push(point(t, 2.0, floor_z(t) + z, Class::Normal));
                pts.push(point(-4.0, t / 2.0, floor_z(-4.0) + z, Class::Normal));
            }
        }
        for k in 0..400 {
            let x = 5.0 + 0.01 * k as f64;
            pts.push(point(x, 0.0, -4.5 - 0.3 * (k % 7) as f64, Class::Normal));
        }
        // Reflections below the floor are no floor.
        for k in 0..3000 {
            pts.push(point(0.001 * k as f64, 1.0, -2.5, Class::Reflection));
        }
        let floor = fit_floor(&pts, &[0.0, 0.1]).unwrap();
        assert!(floor.normal.z > 0.99);
        for x in [-3.0, 0.0, 3.0] {
            let p = Point3::new(x, 0.5, floor_z(x));
            assert!(floor.signed_distance(&p).abs() < 0.02, "x = {x}");
        }
        // Height above it: the ceiling 3 m up at both ends.
        let ceiling = Point3::new(3.5, 0.0, floor_z(3.5) + 3.0);
        assert!((floor.signed_distance(&ceiling) - 3.0 * floor.normal.z).abs() < 0.05);
        // Nothing below the sensor: no floor.
        assert_eq!(fit_floor(&pts, &[-10.0]), None);
        assert_eq!(fit_floor(&[], &[]), None);
    }
}
