//! Observed surfaces of a whole sequence, for the mirror-support test.
//!
//! The paper's last classification step mirrors undecided behind-plane
//! points back through their plane and looks for Normal points nearby; with
//! the Normal points of *all* frames (not only the current one) a reflection
//! of a surface seen from elsewhere in the sequence is recognised too.

use nalgebra::{Isometry3, Point3};

use super::decide::SurfaceSupport;
use crate::geometry::voxel::{packed_voxel_key, FxHashSet};

/// A k-d tree of observed surface points in the world frame, thinned to one
/// point per voxel so its size is bounded by the scene, not the sequence.
pub struct WorldSupport {
    tree: Option<kiddo::ImmutableKdTree<f64, 3>>,
    points: usize,
}

impl std::fmt::Debug for WorldSupport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldSupport")
            .field("points", &self.points)
            .finish()
    }
}

impl WorldSupport {
    /// Build from world-frame points, keeping the first point of each
    /// `voxel`-sized cube (deterministic for a given input order).
    pub fn build(points: impl IntoIterator<Item = Point3<f64>>, voxel: f64) -> Self {
        let points = points.into_iter();
        let mut seen =
            FxHashSet::with_capacity_and_hasher(points.size_hint().0 / 4, Default::default());
        let mut kept: Vec<[f64; 3]> = Vec::new();
        for p in points {
            if seen.insert(packed_voxel_key([p.x, p.y, p.z], voxel)) {
                kept.push([p.x, p.y, p.z]);
            }
        }
        let tree = if kept.is_empty() {
            None
        } else {
            kiddo::ImmutableKdTree::new_from_slice(&kept).ok()
        };
        Self {
            tree,
            points: kept.len(),
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

    /// Whether a kept point lies within `radius` of `p` (world frame).
    pub fn near_world(&self, p: &Point3<f64>, radius: f64) -> bool {
        let Some(tree) = &self.tree else {
            return false;
        };
        let r2 = radius * radius;
        let nn = tree
            .query(&[p.x, p.y, p.z])
            .nearest_one::<kiddo::SquaredEuclidean<f64>>()
            .execute();
        nn.distance <= r2
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
