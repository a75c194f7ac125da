//! Points where planes are not enough: a frame's surface samples and the
//! local map of points they are registered against.
//!
//! The planes fix a pose only in the directions their normals span. In a
//! corridor (floor, ceiling, two parallel walls) the translation along it is
//! free, and the motion model alone carries it: on the simulated mirror room
//! the tracker lost 1.7 m over a 6 m corridor that way. Door frames, end
//! walls and furniture do constrain it, but they are too small to be plane
//! landmarks. So every frame also keeps a thinned set of its points with
//! their surface normals ([`ScanSamples`]), the tracker keeps a bounded
//! local map of earlier frames' samples in the world frame
//! ([`LocalPointMap`], a voxel hash like KISS-ICP's), and the directions the
//! planes leave free are refined by point-to-plane registration against it
//! ([`crate::registration::refine_free_directions`]).
//!
//! Reflections must not enter that map: a mirror image is a consistent
//! phantom. Samples behind a reflective plane of the frame or of the map
//! (within its extent) are left out.

use std::collections::{HashMap, HashSet};

use foldhash::fast::FixedState;

use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
pub use crate::registration::SurfaceSample;
use crate::sensor::OrganizedScan;

/// Settings of the point term (`[slam.points]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointParams {
    /// Refine the directions the planes leave free with points.
    pub enabled: bool,
    /// Edge of the voxels a frame is thinned with (one sample per voxel), m.
    pub sample_voxel: f64,
    /// Edge of the local map's voxels, m.
    pub map_voxel: f64,
    /// Samples kept per map voxel (the first ones; later ones are dropped).
    ///
    /// [`MAX_POINTS_PER_VOXEL`] in every configuration (no key).
    #[serde(skip, default = "max_points_per_voxel")]
    pub max_points_per_voxel: usize,
    /// Map voxels farther than this from the sensor are forgotten, m: the
    /// map's memory is bounded by the space around the sensor, not by the
    /// frames.
    ///
    /// [`MAP_RADIUS`] in every configuration (no key).
    #[serde(skip, default = "map_radius")]
    pub map_radius: f64,
    /// Samples nearer the sensor than this are ignored (the platform and
    /// its operator), m.
    ///
    /// [`MIN_RANGE`] in every configuration (no key).
    #[serde(skip, default = "min_range")]
    pub min_range: f64,
    /// A sample and its nearest map point farther apart than this are no
    /// correspondence, m.
    pub max_correspondence: f64,
    /// Scale of the Cauchy kernel on point-to-plane residuals, m.
    ///
    /// [`KERNEL_SCALE`] in every configuration (no key).
    #[serde(skip, default = "kernel_scale")]
    pub kernel_scale: f64,
    /// Gauss–Newton iterations of the point refinement.
    ///
    /// [`MAX_ITERATIONS`] in every configuration (no key).
    #[serde(skip, default = "max_iterations")]
    pub max_iterations: usize,
    /// A free direction counts as fixed by points when their information
    /// along it reaches this (about the number of samples whose surface
    /// faces along it, each weighted by its kernel weight).
    ///
    /// [`MIN_INFORMATION`] in every configuration (no key).
    #[serde(skip, default = "min_information")]
    pub min_information: f64,
    /// Samples take part in the refinement of a free direction only when
    /// their surface faces along it at least this much (`|n · v|`; see
    /// [`PointRefineParams::min_alignment`](crate::registration::PointRefineParams::min_alignment)).
    ///
    /// [`MIN_ALIGNMENT`] in every configuration (no key).
    #[serde(skip, default = "min_alignment")]
    pub min_alignment: f64,
    /// Samples behind a reflective plane within this margin of its extent
    /// are left out (they may be mirror images), m.
    ///
    /// [`REFLECTIVE_MARGIN`] in every configuration (no key).
    #[serde(skip, default = "reflective_margin")]
    pub reflective_margin: f64,
    /// ... except behind a reflective plane that every free direction of
    /// the frame lies in, within this angle (degrees; absent: none excepted): a
    /// mirror image moves exactly like the real world under a translation
    /// parallel to the mirror, so for a glass-lined corridor's axis what is
    /// seen through or in its walls measures the axis as well as what is
    /// not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parallel_reflective_deg: Option<f64>,
}

/// Samples kept per voxel of the local point map (the first ones; later
/// ones are dropped).
pub const MAX_POINTS_PER_VOXEL: usize = 20;

/// Local-map voxels farther than this from the sensor are forgotten, m.
pub const MAP_RADIUS: f64 = 30.0;

/// Samples nearer the sensor than this are ignored (the platform and its
/// operator), m.
pub const MIN_RANGE: f64 = 0.5;

/// Scale of the Cauchy kernel on point-to-plane residuals, m.
pub const KERNEL_SCALE: f64 = 0.05;

/// Gauss–Newton iterations of the point refinement.
pub const MAX_ITERATIONS: usize = 10;

/// Information (about the number of samples facing along it, kernel
/// weighted) that fixes a free direction by points.
pub const MIN_INFORMATION: f64 = 20.0;

/// Samples refine a free direction only when their surface faces along it
/// at least this much (`|n · v|`).
pub const MIN_ALIGNMENT: f64 = 0.3;

/// Samples behind a reflective plane within this margin of its extent are
/// left out (they may be mirror images), m.
pub const REFLECTIVE_MARGIN: f64 = 0.5;

fn max_points_per_voxel() -> usize {
    MAX_POINTS_PER_VOXEL
}

fn map_radius() -> f64 {
    MAP_RADIUS
}

fn min_range() -> f64 {
    MIN_RANGE
}

fn kernel_scale() -> f64 {
    KERNEL_SCALE
}

fn max_iterations() -> usize {
    MAX_ITERATIONS
}

fn min_information() -> f64 {
    MIN_INFORMATION
}

fn min_alignment() -> f64 {
    MIN_ALIGNMENT
}

fn reflective_margin() -> f64 {
    REFLECTIVE_MARGIN
}

impl Default for PointParams {
    /// `[slam.points]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.points")
    }
}

/// A frame thinned to one sample per voxel, each with its surface normal
/// from the neighbouring beams (sensor frame). Points whose neighbours span
/// no surface are not sampled.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScanSamples {
    /// The samples, in the order of the frame's points.
    pub samples: Vec<SurfaceSample>,
    /// The frame's timestamp, s (`None` when unknown). It travels with the
    /// samples so that the tracker sees the frame's time wherever the
    /// samples are handed to it
    /// ([`Tracker::track_with_samples`](super::Tracker::track_with_samples)).
    pub stamp: Option<f64>,
}

impl ScanSamples {
    /// Sample `frame` (organized as `scan`): the first point of every
    /// `voxel`-sized cell that has a surface normal, beyond `min_range`.
    pub fn sample(frame: &Frame, scan: &OrganizedScan, voxel: f64, min_range: f64) -> Self {
        let mut taken: HashSet<[i32; 3], FixedState> = HashSet::with_hasher(FixedState::default());
        let mut samples = Vec::new();
        for (i, pt) in frame.points.iter().enumerate() {
            let p = pt.position();
            if !(p.coords.norm() >= min_range) {
                continue;
            }
            let key = voxel_key(&p, voxel);
            if taken.contains(&key) {
                continue;
            }
            if let Some(normal) = scan.local_normal(frame, i) {
                taken.insert(key);
                samples.push(SurfaceSample { point: p, normal });
            }
        }
        Self {
            samples,
            stamp: Some(frame.stamp),
        }
    }

    /// The samples not behind any of `reflective` (sensor frame) within
    /// its extent grown by `margin`: what is seen through or in a
    /// reflective plane may be a mirror image.
    pub fn without_reflections(
        &self,
        reflective: &[BoundedPlane],
        margin: f64,
    ) -> Vec<SurfaceSample> {
        let origin = Point3::origin();
        self.samples
            .iter()
            .filter(|s| {
                !reflective.iter().any(|bp| {
                    let r = s.point.coords.norm();
                    let dir = s.point.coords / r;
                    bp.plane.ray_intersection(&origin, &dir).is_some_and(|t| {
                        t < r && bp.bounds_2d(&bp.chart.to_2d(&Point3::from(dir * t)), margin)
                    })
                })
            })
            .copied()
            .collect()
    }
}

/// Voxels by integer key, hashed with a fixed seed (deterministic, and far
/// faster than the default SipHash on three integers).
type VoxelMap<T> = HashMap<[i32; 3], T, FixedState>;

/// The voxel holding `p` for voxels of edge `voxel`.
fn voxel_key(p: &Point3<f64>, voxel: f64) -> [i32; 3] {
    [
        (p.x / voxel).floor() as i32,
        (p.y / voxel).floor() as i32,
        (p.z / voxel).floor() as i32,
    ]
}

/// Earlier frames' samples around the sensor (world frame), in voxels of a
/// fixed edge with a bounded number of points each; voxels beyond a radius
/// of the sensor are dropped, so memory follows the space around the
/// sensor, not the length of the sequence.
#[derive(Debug, Clone, Default)]
pub struct LocalPointMap {
    voxel: f64,
    max_per_voxel: usize,
    /// Points (world frame) with the index of the frame that added them.
    voxels: VoxelMap<Vec<(Point3<f64>, usize)>>,
}

impl LocalPointMap {
    /// An empty map with voxels of edge `voxel` holding at most
    /// `max_per_voxel` points.
    pub fn new(voxel: f64, max_per_voxel: usize) -> Self {
        Self {
            voxel,
            max_per_voxel: max_per_voxel.max(1),
            voxels: HashMap::with_hasher(FixedState::default()),
        }
    }

    /// Whether the map holds no point.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.voxels.values().map(Vec::len).sum()
    }

    /// Add `samples` (sensor frame) of frame `frame` seen from `pose`
    /// (`T_world_sensor`).
    pub fn insert(&mut self, samples: &[SurfaceSample], pose: &Isometry3<f64>, frame: usize) {
        for s in samples {
            let p = pose * s.point;
            let cell = self.voxels.entry(voxel_key(&p, self.voxel)).or_default();
            if cell.len() < self.max_per_voxel {
                cell.push((p, frame));
            }
        }
    }

    /// Add one point (world frame) of frame `frame`.
    pub fn insert_point(&mut self, p: Point3<f64>, frame: usize) {
        let cell = self.voxels.entry(voxel_key(&p, self.voxel)).or_default();
        if cell.len() < self.max_per_voxel {
            cell.push((p, frame));
        }
    }

    /// The points added by frames `frames` (world frame, with their frame),
    /// in a fixed order (by frame, then coordinates): deterministic.
    pub fn points_of(&self, frames: std::ops::RangeInclusive<usize>) -> Vec<(Point3<f64>, usize)> {
        let mut out: Vec<(Point3<f64>, usize)> = self
            .voxels
            .values()
            .flatten()
            .filter(|(_, f)| frames.contains(f))
            .copied()
            .collect();
        out.sort_by(|a, b| {
            a.1.cmp(&b.1)
                .then(a.0.x.total_cmp(&b.0.x))
                .then(a.0.y.total_cmp(&b.0.y))
                .then(a.0.z.total_cmp(&b.0.z))
        });
        out
    }

    /// Move every point by the correction of the frame that added it
    /// (`correction(frame)`, world to world; `None`: leave it), after a
    /// back-end moved the poses (a loop closure). Points are re-binned.
    pub fn correct(&mut self, correction: impl Fn(usize) -> Option<Isometry3<f64>>) {
        let old = std::mem::take(&mut self.voxels);
        // Re-binned in a fixed order: deterministic voxel contents.
        let mut points: Vec<(Point3<f64>, usize)> = old.into_values().flatten().collect();
        points.sort_by(|a, b| {
            a.1.cmp(&b.1)
                .then(a.0.x.total_cmp(&b.0.x))
                .then(a.0.y.total_cmp(&b.0.y))
                .then(a.0.z.total_cmp(&b.0.z))
        });
        for (p, frame) in points {
            let q = correction(frame).map_or(p, |c| c * p);
            let cell = self.voxels.entry(voxel_key(&q, self.voxel)).or_default();
            if cell.len() < self.max_per_voxel {
                cell.push((q, frame));
            }
        }
    }

    /// Forget the voxels whose first point lies farther than `radius` from
    /// `centre`.
    pub fn forget_beyond(&mut self, centre: &Point3<f64>, radius: f64) {
        let r2 = radius * radius;
        self.voxels.retain(|_, pts| {
            pts.first()
                .is_some_and(|(p, _)| (p - centre).norm_squared() <= r2)
        });
    }

    /// The map point nearest to `p` (world frame) within `max_distance`
    /// (at most one voxel edge: the neighbouring voxels are searched), with
    /// the index of the frame that added it.
    pub fn nearest(&self, p: &Point3<f64>, max_distance: f64) -> Option<(Point3<f64>, usize)> {
        let [x, y, z] = voxel_key(p, self.voxel);
        let mut best = None;
        let mut best_d2 = max_distance * max_distance;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(pts) = self.voxels.get(&[x + dx, y + dy, z + dz]) else {
                        continue;
                    };
                    for (q, frame) in pts {
                        let d2 = (q - p).norm_squared();
                        if d2 < best_d2 {
                            best_d2 = d2;
                            best = Some((*q, *frame));
                        }
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn nearest_finds_the_closest_point_across_voxels_and_respects_the_limit() {
        let mut map = LocalPointMap::new(0.5, 20);
        let samples = [
            SurfaceSample {
                point: Point3::new(0.49, 0.0, 0.0),
                normal: Vector3::x(),
            },
            SurfaceSample {
                point: Point3::new(1.2, 0.0, 0.0),
                normal: Vector3::x(),
            },
        ];
        map.insert(&samples, &Isometry3::translation(1.0, 0.0, 0.0), 4);
        assert_eq!(map.len(), 2);
        // 1.49 and 2.2 in the world: 1.55 is nearest to 1.49 (next voxel).
        let (q, frame) = map.nearest(&Point3::new(1.55, 0.0, 0.0), 0.3).unwrap();
        assert!((q.x - 1.49).abs() < 1e-12);
        assert_eq!(frame, 4);
        assert!(map.nearest(&Point3::new(1.85, 0.0, 0.0), 0.3).is_none());
    }

    #[test]
    fn voxels_are_capped_and_far_ones_forgotten() {
        let mut map = LocalPointMap::new(1.0, 3);
        let samples: Vec<SurfaceSample> = (0..10)
            .map(|k| SurfaceSample {
                point: Point3::new(0.05 * k as f64, 0.0, 0.0),
                normal: Vector3::x(),
            })
            .collect();
        map.insert(&samples, &Isometry3::identity(), 0);
        map.insert(&samples, &Isometry3::translation(50.0, 0.0, 0.0), 1);
        assert_eq!(map.len(), 6);
        map.forget_beyond(&Point3::origin(), 10.0);
        assert_eq!(map.len(), 3);
    }
}
