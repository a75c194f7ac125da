//! Observed surfaces of a whole sequence, for the mirror-support test.
//!
//! The paper's last classification step mirrors undecided behind-plane
//! points back through their plane and looks for Normal points nearby; with
//! the Normal points of *all* frames (not only the current one) a reflection
//! of a surface seen from elsewhere in the sequence is recognised too.
//!
//! The points are thinned to one per small voxel and bucketed in cubes as
//! large as the query radius, so "is there a point within r" inspects at most
//! 27 buckets; building it is a linear pass (no tree to balance), which
//! matters because it is rebuilt for every run over all frames.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use nalgebra::{Isometry3, Point3};

use super::decide::SurfaceSupport;
use crate::geometry::voxel::{packed_voxel_key, voxel_key, FxHashSet, FxHasher};

/// Observed surface points in the world frame, answering radius queries.
pub struct WorldSupport {
    radius: f64,
    buckets: HashMap<[i64; 3], Vec<[f32; 3]>, BuildHasherDefault<FxHasher>>,
    points: usize,
}

impl std::fmt::Debug for WorldSupport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldSupport")
            .field("points", &self.points)
            .field("radius", &self.radius)
            .finish()
    }
}

impl WorldSupport {
    /// Build from world-frame points, keeping the first point of each
    /// `voxel`-sized cube (deterministic for a given input order), for
    /// queries of radius up to `radius`.
    pub fn build(points: impl IntoIterator<Item = Point3<f64>>, voxel: f64, radius: f64) -> Self {
        let points = points.into_iter();
        let radius = radius.max(voxel).max(1e-3);
        let mut seen =
            FxHashSet::with_capacity_and_hasher(points.size_hint().0 / 4, Default::default());
        let mut buckets: HashMap<[i64; 3], Vec<[f32; 3]>, BuildHasherDefault<FxHasher>> =
            HashMap::default();
        let mut count = 0;
        for p in points {
            let xyz = [p.x, p.y, p.z];
            if seen.insert(packed_voxel_key(xyz, voxel)) {
                buckets
                    .entry(voxel_key(xyz, radius))
                    .or_default()
                    .push([p.x as f32, p.y as f32, p.z as f32]);
                count += 1;
            }
        }
        Self {
            radius,
            buckets,
            points: count,
        }
    }

    /// Number of points kept.
    pub fn len(&self) -> usize {
        self.points
    }

    /// Whether no point was kept.
    pub fn is_empty(&self) -> bool {
        self.points == 0
    }

    /// Whether a kept point lies within `radius` of `p` (world frame);
    /// `radius` is clamped to the radius the support was built for.
    pub fn near_world(&self, p: &Point3<f64>, radius: f64) -> bool {
        let r = radius.min(self.radius);
        let r2 = (r * r) as f32;
        let c = voxel_key([p.x, p.y, p.z], self.radius);
        let q = [p.x as f32, p.y as f32, p.z as f32];
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(bucket) = self.buckets.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    if bucket.iter().any(|b| {
                        let (x, y, z) = (b[0] - q[0], b[1] - q[1], b[2] - q[2]);
                        x * x + y * y + z * z <= r2
                    }) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// A view answering in the sensor frame of a frame with pose `pose`.
    pub fn in_sensor_frame(&self, pose: Isometry3<f64>) -> SensorFrameSupport<'_> {
        SensorFrameSupport { world: self, pose }
    }
}

/// [`WorldSupport`] seen from one sensor pose.
pub struct SensorFrameSupport<'a> {
    world: &'a WorldSupport,
    pose: Isometry3<f64>,
}

impl SurfaceSupport for SensorFrameSupport<'_> {
    fn near(&self, p: &Point3<f64>, radius: f64) -> bool {
        self.world.near_world(&(self.pose * p), radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_queries_match_brute_force() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let pts: Vec<Point3<f64>> = (0..2000)
            .map(|_| Point3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 4.0 - 2.0, rng.unit()))
            .collect();
        let support = WorldSupport::build(pts.iter().copied(), 1e-6, 0.3);
        assert_eq!(support.len(), 2000);
        for _ in 0..500 {
            let q = Point3::new(
                rng.unit() * 5.0 - 2.5,
                rng.unit() * 5.0 - 2.5,
                rng.unit() * 1.5 - 0.25,
            );
            for r in [0.05, 0.2, 0.3] {
                let brute = pts.iter().any(|p| (p - q).norm() <= r - 1e-6);
                let fast = support.near_world(&q, r);
                if brute {
                    assert!(fast, "missed a point within {r} of {q}");
                }
                if fast {
                    assert!(pts.iter().any(|p| (p - q).norm() <= r + 1e-5));
                }
            }
        }
    }
}
