//! Observed surfaces of a whole sequence, for the mirror-support test.
//!
//! The paper's last classification step mirrors undecided behind-plane
//! points back through their plane and looks for Normal points nearby; with
//! the Normal points of *all* frames (not only the current one) a reflection
//! of a surface seen from elsewhere in the sequence is recognised too.
//!
//! The points are thinned to one per small voxel and bucketed in cubes as
//! large as the query radius, so "is there a point within r" inspects at most
//! 8 buckets; building it is two linear passes (no tree to balance), which
//! matters because it is rebuilt for every run over all frames. The buckets
//! are ranges of one flat array (a counting sort), not a vector each.

use nalgebra::{Isometry3, Point3};

use super::decide::SurfaceSupport;
use crate::geometry::fastmath::floor_i64;
use crate::geometry::voxel::{FxHashMap, VoxelSet};

/// Observed surface points in the world frame, answering radius queries.
pub struct WorldSupport {
    radius: f64,
    /// Bucket key (packed cube of edge `radius`) to bucket number.
    buckets: FxHashMap<u64, u32>,
    /// Bucket `b` holds `points[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    points: Vec<[f32; 3]>,
}

impl std::fmt::Debug for WorldSupport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldSupport")
            .field("points", &self.points.len())
            .field("radius", &self.radius)
            .finish()
    }
}

/// A cube's integer coordinates packed into one key: 21 bits per axis, two's
/// complement, exact within ±2^20 cubes (±330 km at 0.3 m); farther away two
/// cubes may share a bucket, which only costs distance tests, never answers.
#[inline]
fn bucket_key(c: [i64; 3]) -> u64 {
    let m = (1u64 << 21) - 1;
    (c[0] as u64 & m) | ((c[1] as u64 & m) << 21) | ((c[2] as u64 & m) << 42)
}

/// Builds a [`WorldSupport`] from points offered a frame at a time: what it
/// keeps grows with the surface seen (one point per voxel), not with the
/// number of frames.
pub struct SupportBuilder {
    radius: f64,
    inv: f64,
    seen: VoxelSet,
    buckets: FxHashMap<u64, u32>,
    /// The kept points with their bucket numbers.
    kept: Vec<(u32, [f32; 3])>,
    /// Points per bucket.
    counts: Vec<u32>,
    /// Consecutive points mostly share a bucket: the last one.
    last: Option<(u64, u32)>,
}

impl SupportBuilder {
    /// An empty support thinned to one point per `voxel`, for queries of
    /// radius up to `radius`.
    pub fn new(voxel: f64, radius: f64) -> Self {
        let radius = radius.max(voxel).max(1e-3);
        Self {
            radius,
            inv: 1.0 / radius,
            seen: VoxelSet::new(voxel),
            buckets: FxHashMap::default(),
            kept: Vec::new(),
            counts: Vec::new(),
            last: None,
        }
    }

    /// Offer world-frame points (the first of each voxel is kept).
    pub fn extend(&mut self, points: impl IntoIterator<Item = Point3<f64>>) {
        let inv = self.inv;
        for p in points {
            let xyz = [p.x, p.y, p.z];
            if !self.seen.insert(xyz, 0) {
                continue;
            }
            let key = bucket_key([
                floor_i64(p.x * inv),
                floor_i64(p.y * inv),
                floor_i64(p.z * inv),
            ]);
            let b = match self.last {
                Some((k, b)) if k == key => b,
                _ => {
                    let next = self.counts.len() as u32;
                    let b = *self.buckets.entry(key).or_insert(next);
                    if b == next {
                        self.counts.push(0);
                    }
                    self.last = Some((key, b));
                    b
                }
            };
            self.counts[b as usize] += 1;
            self.kept.push((b, [p.x as f32, p.y as f32, p.z as f32]));
        }
    }

    /// The support: a counting sort of the kept points into one array,
    /// input order kept per bucket.
    pub fn finish(self) -> WorldSupport {
        let mut starts = Vec::with_capacity(self.counts.len() + 1);
        let mut total = 0u32;
        starts.push(0);
        for &c in &self.counts {
            total += c;
            starts.push(total);
        }
        let mut fill: Vec<u32> = starts[..self.counts.len()].to_vec();
        let mut flat = vec![[0f32; 3]; self.kept.len()];
        for (b, q) in self.kept {
            let slot = &mut fill[b as usize];
            flat[*slot as usize] = q;
            *slot += 1;
        }
        WorldSupport {
            radius: self.radius,
            buckets: self.buckets,
            starts,
            points: flat,
        }
    }
}

impl WorldSupport {
    /// Build from world-frame points, keeping the first point of each
    /// `voxel`-sized cube (deterministic for a given input order), for
    /// queries of radius up to `radius`.
    pub fn build(points: impl IntoIterator<Item = Point3<f64>>, voxel: f64, radius: f64) -> Self {
        let mut builder = SupportBuilder::new(voxel, radius);
        builder.extend(points);
        builder.finish()
    }

    /// Number of points kept.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no point was kept.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Whether a kept point lies within `radius` of `p` (world frame);
    /// `radius` is clamped to the radius the support was built for.
    pub fn near_world(&self, p: &Point3<f64>, radius: f64) -> bool {
        let r = radius.min(self.radius);
        let r2 = (r * r) as f32;
        let inv = 1.0 / self.radius;
        let xyz = [p.x, p.y, p.z];
        // The cubes the query ball overlaps: one or two per axis.
        let lo = xyz.map(|v| floor_i64((v - r) * inv));
        let hi = xyz.map(|v| floor_i64((v + r) * inv));
        let q = xyz.map(|v| v as f32);
        for cx in lo[0]..=hi[0] {
            for cy in lo[1]..=hi[1] {
                for cz in lo[2]..=hi[2] {
                    let Some(&b) = self.buckets.get(&bucket_key([cx, cy, cz])) else {
                        continue;
                    };
                    let range =
                        self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
                    if self.points[range].iter().any(|b| {
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
