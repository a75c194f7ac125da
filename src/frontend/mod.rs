//! The SLAM front end: the planes of one frame.
//!
//! The paper's "Extraction of ordinary Planes from filtered Point Clouds",
//! step by step, one file per concept:
//!
//! 1. [`filter`]: remove what reflections touched — the detector's candidate
//!    points and every point seen *through* a detected reflective plane —
//!    and keep at most one point per (ring, column) cell ([`CellCloud`]).
//! 2. [`ground`]: fit the ground plane first, to the points below the
//!    sensor (`z < 0`), and store it separately (kind `Ground`).
//! 3. [`normals`]: a normal per cell by PCA over its ring ± 1, column ± 1
//!    neighbours (an organized neighbourhood: no search structure, no
//!    per-point allocation).
//! 4. [`region_growing`]: segments of cells whose normals agree and whose
//!    points are close (PCL's region growing on the organized grid).
//! 5. [`extractor`]: RANSAC per segment from the largest, at most 25
//!    planes, the paper's acceptance rule on inliers, area and density, and
//!    the hull, centroid and area of every plane ([`FramePlane`]).
//!
//! The reflective planes of the [`ReflectiveDetector`](crate::reflect::ReflectiveDetector)
//! join the frame's planes as their own kind ([`reflective`]: the largest
//! connected patch of each plane's inliers, refitted).
//! Extractors are selected by name ([`ExtractorParams::name`], no key) through the
//! [`PlaneExtractor`] trait.

pub mod extractor;
pub mod filter;
pub mod ground;
pub mod normals;
pub mod reflective;
pub mod region_growing;

pub use extractor::{ExtractorName, ExtractorParams, RegionGrowingExtractor};
pub use filter::CellCloud;
pub use normals::{NormalParams, OrganizedNormals};
pub use reflective::reflective_planes;
pub use region_growing::RegionParams;

use nalgebra::{Isometry3, Matrix3, Point2, Point3, Vector3};

use crate::cloud::Frame;
use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::io::PlaneKind;
use crate::map::PlaneObservation;
use crate::reflect::Detection;
use crate::sensor::OrganizedScan;

/// One bounded plane of a frame (sensor frame unless transformed), with
/// what plane matching needs: hull, centroid and area.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlane {
    /// Ordinary, ground or reflective.
    pub kind: PlaneKind,
    /// The plane, facing the sensor (`d > 0` in the sensor frame).
    pub plane: Plane,
    /// The chart the hull is expressed in.
    pub chart: PlaneChart,
    /// Convex hull of the inliers projected into the chart.
    pub hull: ConvexPolygon,
    /// Mean of the inliers (the paper's "plane centroid").
    pub centroid: Point3<f64>,
    /// Hull area, m².
    pub area: f64,
    /// Indices of the inliers in the frame's points.
    pub inliers: Vec<u32>,
    /// Centred scatter of the inliers, `Σ (p - c)(p - c)ᵀ` about the
    /// centroid: with the count and centroid it summarises every
    /// point-to-plane residual of the observation (the back-end's
    /// point-to-plane factor).
    pub scatter: Matrix3<f64>,
}

/// Centroid and centred scatter of `inliers` of `frame` (the origin and zero
/// for no inliers).
pub fn inlier_moments(frame: &Frame, inliers: &[u32]) -> (Point3<f64>, Matrix3<f64>) {
    if inliers.is_empty() {
        return (Point3::origin(), Matrix3::zeros());
    }
    let n = inliers.len() as f64;
    let sum: Vector3<f64> = inliers
        .iter()
        .map(|&i| frame.points[i as usize].position().coords)
        .sum();
    let c = sum / n;
    let mut scatter = Matrix3::zeros();
    for &i in inliers {
        let r = frame.points[i as usize].position().coords - c;
        scatter += r * r.transpose();
    }
    (Point3::from(c), scatter)
}

impl FramePlane {
    /// A plane bounded by its inliers (`None` when the hull is degenerate).
    /// The plane is oriented to face the sensor origin.
    pub fn from_inliers(
        kind: PlaneKind,
        plane: Plane,
        frame: &Frame,
        inliers: Vec<u32>,
    ) -> Option<Self> {
        let plane = plane.facing(&Point3::origin());
        let chart = PlaneChart::of(&plane);
        let uv: Vec<_> = inliers
            .iter()
            .map(|&i| chart.to_2d(&frame.points[i as usize].position()))
            .collect();
        let hull = hull_of(uv);
        if hull.is_empty() {
            return None;
        }
        let (centroid, scatter) = inlier_moments(frame, &inliers);
        Some(Self {
            kind,
            plane,
            chart,
            area: hull.area(),
            hull,
            centroid,
            inliers,
            scatter,
        })
    }

    /// The same plane in another frame (`t` maps the current frame to the
    /// new one); the hull polygon stays valid in the transformed chart.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        Self {
            kind: self.kind,
            plane: self.plane.transformed(t),
            chart: self.chart.transformed(t),
            hull: self.hull.clone(),
            centroid: t * self.centroid,
            area: self.area,
            inliers: self.inliers.clone(),
            scatter: {
                let r = t.rotation.to_rotation_matrix().into_inner();
                r * self.scatter * r.transpose()
            },
        }
    }

    /// Hull vertices in 3-D (the frame this plane is expressed in).
    pub fn hull_3d(&self) -> Vec<Point3<f64>> {
        self.hull
            .vertices()
            .iter()
            .map(|q| self.chart.to_3d(q))
            .collect()
    }

    /// This plane as a world-frame map observation of frame `frame`, given
    /// the frame's pose `T_world_sensor`.
    pub fn observation(&self, pose: &Isometry3<f64>, frame: usize) -> PlaneObservation {
        PlaneObservation {
            kind: self.kind,
            plane: self.plane.transformed(pose),
            boundary: self.hull_3d().iter().map(|p| pose * p).collect(),
            frame,
        }
    }
}

/// The convex hull of many chart points, faster: points strictly inside
/// the octagon of the extreme points in x, y, x + y and x − y cannot be
/// hull vertices and are dropped before [`ConvexPolygon::hull`] sorts the
/// rest (Akl–Toussaint); most of a plane's inliers are interior.
pub fn hull_of(mut uv: Vec<Point2<f64>>) -> ConvexPolygon {
    if uv.len() > 64 {
        let keys = |p: &Point2<f64>| [p.x, p.y, p.x + p.y, p.x - p.y];
        let (mut lo, mut hi) = ([0usize; 4], [0usize; 4]);
        let (mut lo_v, mut hi_v) = (keys(&uv[0]), keys(&uv[0]));
        for (i, p) in uv.iter().enumerate() {
            let k = keys(p);
            for a in 0..4 {
                if k[a] < lo_v[a] {
                    lo_v[a] = k[a];
                    lo[a] = i;
                }
                if k[a] > hi_v[a] {
                    hi_v[a] = k[a];
                    hi[a] = i;
                }
            }
        }
        // The octagon, counter-clockwise: min y, max x−y, max x, max x+y,
        // max y, min x−y, min x, min x+y.
        let octagon = [lo[1], hi[3], hi[0], hi[2], hi[1], lo[3], lo[0], lo[2]].map(|i| uv[i]);
        let inside = |p: &Point2<f64>| {
            (0..8).all(|e| {
                let (a, b) = (octagon[e], octagon[(e + 1) % 8]);
                (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x) > 0.0
            })
        };
        uv.retain(|p| !inside(p));
    }
    ConvexPolygon::hull(&uv)
}

/// Extracts the ordinary planes (and the ground plane) of one frame.
/// Implementations are selected by name in the configuration
/// ([`ExtractorParams::name`], no key).
pub trait PlaneExtractor: Send + Sync {
    /// The name this extractor is selected by.
    fn name(&self) -> &'static str;

    /// The ground plane (if found) and the ordinary planes of `frame`, in the
    /// sensor frame, after removing the points that reflections touched
    /// according to `detection`. `seed` makes the randomised parts
    /// deterministic.
    fn extract(
        &self,
        frame: &Frame,
        scan: &OrganizedScan,
        detection: &Detection,
        seed: u64,
    ) -> Vec<FramePlane>;
}

/// Synthetic scans for the tests: the QT64 beam pattern cast against
/// rectangles.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_octagon_filter_keeps_the_hull() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for n in [10, 65, 500, 5000] {
            let pts: Vec<Point2<f64>> = (0..n)
                .map(|_| Point2::new(rng.normal() * 3.0, rng.unit() * 2.0 - 1.0))
                .collect();
            assert_eq!(
                hull_of(pts.clone()),
                ConvexPolygon::hull(&pts),
                "{n} points"
            );
        }
    }
}

#[cfg(test)]
pub(crate) mod testing {
    use nalgebra::{Point2, Point3};

    use crate::cloud::{Frame, Point};
    use crate::geometry::{Plane, PlaneChart};
    use crate::sensor::SensorModel;

    /// A rectangle `[min, max]` in the canonical chart of `plane`.
    pub struct Rect {
        pub plane: Plane,
        pub min: Point2<f64>,
        pub max: Point2<f64>,
    }

    impl Rect {
        /// The axis-aligned rectangle spanned by two opposite corners lying
        /// on one coordinate plane (x, y or z constant).
        pub fn between(a: Point3<f64>, b: Point3<f64>) -> Self {
            let axis = (0..3).find(|&k| (a[k] - b[k]).abs() < 1e-12).expect("flat");
            let mut n = nalgebra::Vector3::zeros();
            n[axis] = 1.0;
            let plane = Plane::from_point_normal(&a, &n).unwrap();
            let chart = PlaneChart::of(&plane);
            let (qa, qb) = (chart.to_2d(&a), chart.to_2d(&b));
            Self {
                plane,
                min: Point2::new(qa.x.min(qb.x), qa.y.min(qb.y)),
                max: Point2::new(qa.x.max(qb.x), qa.y.max(qb.y)),
            }
        }
    }

    /// One return per beam of the QT64 pattern at the nearest rectangle hit
    /// (label 1), with deterministic range noise of `noise` m.
    pub fn cast(rects: &[Rect], noise: f64) -> Frame {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut points = Vec::new();
        for ring in 0..sensor.rings() {
            for col in 0..sensor.columns {
                let dir = sensor.beam_direction(ring, col);
                let mut best = f64::INFINITY;
                for r in rects {
                    let Some(t) = r.plane.ray_intersection(&Point3::origin(), &dir) else {
                        continue;
                    };
                    let q = PlaneChart::of(&r.plane).to_2d(&Point3::from(dir * t));
                    if q.x >= r.min.x && q.x <= r.max.x && q.y >= r.min.y && q.y <= r.max.y {
                        best = best.min(t);
                    }
                }
                if best.is_finite() && best < 25.0 {
                    let p = dir * (best + noise * rng.normal());
                    points.push(Point {
                        xyz: [p.x as f32, p.y as f32, p.z as f32],
                        intensity: 20.0,
                        ring: ring as u16,
                        ret: 1,
                        label: 1,
                        time: 0.0,
                    });
                }
            }
        }
        Frame {
            name: "synthetic".into(),
            stamp: 0.0,
            points,
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        }
    }
}
