//! The classified world maps a run writes, built a frame at a time and
//! thinned by voxel: the measured map, and the "around the corner" map with
//! reflections mirrored back to where they really are.

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use crate::classify::mirror::mirror_reflections;
use crate::classify::Class;
use crate::cloud::Frame;
use crate::geometry::voxel::VoxelSet;
use crate::io::MapPoint;
use crate::pipeline::Sequence;
use crate::reflect::{planes_seen_from, BoundedPlane};
use crate::Result;

/// The classified map in the world frame ("around the corner"), built a
/// frame at a time: Normal, reflective-surface and Obstacle points where
/// they were measured, Reflections mirrored back through their plane;
/// unclassified points are left out. Thinned to one point per `voxel` per
/// class (0 keeps all), so it grows with the space mapped, not with the
/// frames.
pub struct AroundCornerMap {
    planes: Vec<BoundedPlane>,
    hull_margin: f64,
    thin: Thinning,
}

impl AroundCornerMap {
    /// An empty map against the reflective `planes` (world frame).
    pub fn new(planes: &[BoundedPlane], hull_margin: f64, voxel: f64) -> Self {
        Self {
            planes: planes.to_vec(),
            hull_margin,
            thin: Thinning::new(voxel),
        }
    }

    /// Add a frame with its pose, classes and their confidences (one per
    /// point, or empty where the method does not say: the map's
    /// `confidence` is then NaN).
    pub fn add(
        &mut self,
        frame: &Frame,
        pose: &Isometry3<f64>,
        classes: &[Class],
        confidence: &[f32],
    ) {
        let planes = planes_seen_from(&self.planes, pose);
        let mirrored = mirror_reflections(frame, classes, &planes, self.hull_margin);
        let (r, t) = rotation_translation(pose);
        for (i, (pt, &class)) in frame.points.iter().zip(classes).enumerate() {
            if matches!(class, Class::Normal | Class::Glass | Class::Obstacle) {
                self.thin.offer(
                    Point3::from(r * pt.position().coords + t),
                    class,
                    false,
                    confidence_at(confidence, i),
                );
            }
        }
        for (i, q) in mirrored {
            self.thin.offer(
                pose * q,
                Class::Reflection,
                true,
                confidence_at(confidence, i),
            );
        }
    }

    /// The map's points, in the order they were kept.
    pub fn into_points(self) -> Vec<MapPoint> {
        self.thin.kept
    }
}

/// The accumulated classified map in the world frame, built a frame at a
/// time: every classified point where it was measured (reflections
/// included, not mirrored); unclassified points are left out. Thinned to
/// one point per `voxel` per class (0 keeps all).
pub struct MeasuredMap {
    thin: Thinning,
}

impl MeasuredMap {
    /// An empty map.
    pub fn new(voxel: f64) -> Self {
        Self {
            thin: Thinning::new(voxel),
        }
    }

    /// Add a frame with its pose, classes and their confidences (one per
    /// point, or empty where the method does not say: the map's
    /// `confidence` is then NaN).
    pub fn add(
        &mut self,
        frame: &Frame,
        pose: &Isometry3<f64>,
        classes: &[Class],
        confidence: &[f32],
    ) {
        for (i, (pt, &class)) in frame.points.iter().zip(classes).enumerate() {
            if class != Class::Unclassified {
                self.thin.offer(
                    pose * pt.position(),
                    class,
                    false,
                    confidence_at(confidence, i),
                );
            }
        }
    }

    /// The map's points, in the order they were kept.
    pub fn into_points(self) -> Vec<MapPoint> {
        self.thin.kept
    }
}

/// [`AroundCornerMap`] of a sequence and its classes (empty without poses;
/// no confidences, the map's are NaN).
pub fn around_corner_map(
    sequence: &Sequence,
    classes: &[Vec<Class>],
    map_planes: &[BoundedPlane],
    hull_margin: f64,
    voxel: f64,
) -> Result<Vec<MapPoint>> {
    let Some(poses) = &sequence.poses else {
        return Ok(Vec::new());
    };
    let mut map = AroundCornerMap::new(map_planes, hull_margin, voxel);
    for k in 0..sequence.len().min(classes.len()) {
        map.add(&*sequence.frame(k)?, &poses[k], &classes[k], &[]);
    }
    Ok(map.into_points())
}

/// [`MeasuredMap`] of a sequence and its classes (empty without poses; no
/// confidences, the map's are NaN).
pub fn measured_map(
    sequence: &Sequence,
    classes: &[Vec<Class>],
    voxel: f64,
) -> Result<Vec<MapPoint>> {
    let Some(poses) = &sequence.poses else {
        return Ok(Vec::new());
    };
    let mut map = MeasuredMap::new(voxel);
    for k in 0..sequence.len().min(classes.len()) {
        map.add(&*sequence.frame(k)?, &poses[k], &classes[k], &[]);
    }
    Ok(map.into_points())
}

/// The confidence of point `i`, NaN when unknown.
fn confidence_at(confidence: &[f32], i: usize) -> f32 {
    confidence.get(i).copied().unwrap_or(f32::NAN)
}

/// A pose as rotation matrix and translation: applied to every point of a
/// frame, the matrix is cheaper than the quaternion.
pub(super) fn rotation_translation(pose: &Isometry3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    (
        pose.rotation.to_rotation_matrix().into_inner(),
        pose.translation.vector,
    )
}

/// Keeps the first point offered per (voxel, class, mirrored), with that
/// point's confidence; a voxel of 0 (or less) keeps every point.
struct Thinning {
    seen: Option<VoxelSet>,
    kept: Vec<MapPoint>,
}

impl Thinning {
    fn new(voxel: f64) -> Self {
        Self {
            seen: (voxel > 0.0).then(|| VoxelSet::new(voxel)),
            kept: Vec::new(),
        }
    }

    /// Offer a point; kept (with its `confidence`) when it is the first of
    /// its voxel, class and mirroring.
    #[inline]
    fn offer(&mut self, p: Point3<f64>, class: Class, mirrored: bool, confidence: f32) {
        let tag = (class.id() & 0x7) | (mirrored as u8) << 3;
        if self
            .seen
            .as_mut()
            .is_none_or(|s| s.insert([p.x, p.y, p.z], tag))
        {
            self.kept.push(MapPoint {
                xyz: [p.x as f32, p.y as f32, p.z as f32],
                class,
                mirrored,
                confidence,
            });
        }
    }
}
