//! The paper's extractor: filtered cloud → ground → normals → region
//! growing → RANSAC per segment → bounded planes.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::filter::{reflection_mask, CellCloud};
use super::ground::{fit_ground, GroundParams};
use super::normals::{NormalParams, OrganizedNormals};
use super::region_growing::{grow_regions, RegionParams};
use super::{FramePlane, PlaneExtractor};
use crate::cloud::Frame;
use crate::geometry::fit::{ransac_plane, remove_positions, RansacParams};
use crate::io::PlaneKind;
use crate::reflect::Detection;
use crate::rng::SplitMix64;
use crate::sensor::OrganizedScan;

/// Plane extractors selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExtractorName {
    /// Region growing on the organized grid, then RANSAC per segment (the
    /// paper, after PCL).
    RegionGrowing,
}

impl ExtractorName {
    /// The name on the command line and in configurations.
    pub fn name(self) -> &'static str {
        match self {
            ExtractorName::RegionGrowing => "region-growing",
        }
    }
}

/// Plane-extraction settings (`[extractor]`); the paper's values are the
/// defaults where it gives them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtractorParams {
    /// The extractor: region growing, the only one (no key).
    #[serde(skip, default = "region_growing")]
    pub name: ExtractorName,
    /// Points more than this far behind a detected reflective plane, seen
    /// through its boundary, are removed before extraction, m.
    pub behind_margin: f64,
    /// Normal estimation.
    pub normals: NormalParams,
    /// Region growing.
    pub region: RegionParams,
    /// The ground plane, fitted first.
    pub ground: GroundParams,
    /// RANSAC per segment: the inlier distance (`[extractor.ransac]
    /// distance`, m) is the only key, the rest [`RANSAC`]'s.
    #[serde(
        serialize_with = "crate::geometry::fit::serialize_distance",
        deserialize_with = "deserialize_ransac"
    )]
    pub ransac: RansacParams,
    /// At most this many ordinary planes per frame: [`MAX_PLANES`].
    #[serde(skip, default = "max_planes")]
    pub max_planes: usize,
    /// A plane needs at least this many inliers (paper: 200), points.
    pub min_points: usize,
    /// A plane needs at least this hull area, m² (paper: 0.3).
    pub min_area: f64,
    /// A plane sparser than this many inliers per m²: [`MIN_DENSITY`] ...
    #[serde(skip, default = "min_density")]
    pub min_density: f64,
    /// ... needs at least this many inliers: [`SPARSE_MIN_POINTS`].
    #[serde(skip, default = "sparse_min_points")]
    pub sparse_min_points: usize,
    /// Reflective planes enter registration as their largest patch of
    /// inliers linked within this distance in the plane, m (see
    /// [`reflective_planes`](super::reflective_planes)); absent: the
    /// detector's plane as it is (the paper).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflective_link: Option<f64>,
}

/// RANSAC per segment but for the inlier distance (a key): at most 100
/// iterations, stopping once an outlier-free sample was drawn with
/// probability 0.99, and a least-squares refit (the paper, after PCL).
pub const RANSAC: RansacParams = RansacParams {
    distance: 0.05,
    max_iterations: 100,
    probability: 0.99,
    refit: true,
};

/// At most this many ordinary planes per frame (the paper: 25).
pub const MAX_PLANES: usize = 25;

/// A plane sparser than this many inliers per m² (the paper: 100) needs
/// [`SPARSE_MIN_POINTS`] inliers.
pub const MIN_DENSITY: f64 = 100.0;

/// The inliers a sparse plane needs (the paper: 500).
pub const SPARSE_MIN_POINTS: usize = 500;

fn deserialize_ransac<'de, D: serde::Deserializer<'de>>(d: D) -> Result<RansacParams, D::Error> {
    crate::geometry::fit::deserialize_distance(d, RANSAC)
}

fn region_growing() -> ExtractorName {
    ExtractorName::RegionGrowing
}

fn max_planes() -> usize {
    MAX_PLANES
}

fn min_density() -> f64 {
    MIN_DENSITY
}

fn sparse_min_points() -> usize {
    SPARSE_MIN_POINTS
}

impl Default for ExtractorParams {
    /// `[extractor]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("extractor")
    }
}

impl ExtractorParams {
    /// The paper's acceptance rule for a plane of `points` inliers and
    /// `area` m² of hull.
    pub fn accepts(&self, points: usize, area: f64) -> bool {
        points >= self.min_points
            && area >= self.min_area
            && (points as f64 / area >= self.min_density || points >= self.sparse_min_points)
    }
}

/// Region growing + RANSAC per segment (the paper's extractor).
#[derive(Debug, Clone, Default)]
pub struct RegionGrowingExtractor {
    params: ExtractorParams,
}

impl RegionGrowingExtractor {
    /// An extractor with the given settings.
    pub fn new(params: ExtractorParams) -> Self {
        Self { params }
    }

    /// The settings.
    pub fn params(&self) -> &ExtractorParams {
        &self.params
    }

    /// Extract from an already filtered cloud (the stages after
    /// [`reflection_mask`]); exposed for tests and benchmarks.
    pub fn extract_cells(&self, frame: &Frame, cells: &CellCloud, seed: u64) -> Vec<FramePlane> {
        let p = &self.params;
        let mut rng = SplitMix64::new(seed);
        let mut normals = OrganizedNormals::default();
        normals.estimate(cells, &p.normals);
        let mut planes = Vec::new();

        // 1. The ground plane first, from the points below the sensor.
        let mut excluded = vec![false; cells.cells()];
        if let Some((plane, members)) =
            fit_ground(cells, &normals, &p.ground, p.min_points, &mut rng)
        {
            for &c in &members {
                excluded[c] = true;
            }
            let inliers = members.iter().filter_map(|&c| cells.point(c)).collect();
            if let Some(fp) = FramePlane::from_inliers(PlaneKind::Ground, plane, frame, inliers) {
                if p.accepts(fp.inliers.len(), fp.area) {
                    planes.push(fp);
                }
            }
        }

        // 2. Segments of consistent normals, largest first.
        let segments = grow_regions(cells, &normals, &excluded, &p.normals, &p.region);

        // 3. RANSAC per segment until no satisfactory plane is left in it,
        //    then the next segment; at most `max_planes` ordinary planes.
        let mut ordinary = 0;
        let mut pts: Vec<Point3<f64>> = Vec::new();
        'segments: for segment in segments {
            let mut remaining = segment;
            while remaining.len() >= p.min_points.max(3) {
                if ordinary >= p.max_planes {
                    break 'segments;
                }
                pts.clear();
                pts.extend(remaining.iter().map(|&c| cells.position(c)));
                let Some(fit) = ransac_plane(&pts, &p.ransac, &mut rng) else {
                    break;
                };
                if fit.inliers.len() < p.min_points {
                    break;
                }
                let inliers: Vec<u32> = fit
                    .inliers
                    .iter()
                    .filter_map(|&k| cells.point(remaining[k as usize]))
                    .collect();
                let Some(fp) =
                    FramePlane::from_inliers(PlaneKind::Ordinary, fit.plane, frame, inliers)
                else {
                    break;
                };
                if !p.accepts(fp.inliers.len(), fp.area) {
                    break;
                }
                planes.push(fp);
                ordinary += 1;
                remove_positions(&mut remaining, &fit.inliers);
            }
        }
        planes
    }
}

impl PlaneExtractor for RegionGrowingExtractor {
    fn name(&self) -> &'static str {
        self.params.name.name()
    }

    fn extract(
        &self,
        frame: &Frame,
        scan: &OrganizedScan,
        detection: &Detection,
        seed: u64,
    ) -> Vec<FramePlane> {
        let removed = reflection_mask(frame, detection, self.params.behind_margin);
        let cells = CellCloud::build(frame, scan, &removed);
        self.extract_cells(frame, &cells, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::testing::{cast, Rect};
    use crate::sensor::SensorModel;
    use nalgebra::{Point3, Vector3};

    #[test]
    fn floor_and_two_walls_give_ground_and_two_ordinary_planes() {
        // A 1.2 m high sensor: floor z = -1.2, walls x = 3 and y = -2.5.
        let frame = cast(
            &[
                Rect::between(Point3::new(-6.0, -2.5, -1.2), Point3::new(3.0, 6.0, -1.2)),
                Rect::between(Point3::new(3.0, -2.5, -1.2), Point3::new(3.0, 6.0, 1.5)),
                Rect::between(Point3::new(-6.0, -2.5, -1.2), Point3::new(3.0, -2.5, 1.5)),
            ],
            0.01,
        );
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let ex = RegionGrowingExtractor::default();
        let planes = ex.extract(&frame, &scan, &Detection::default(), 1);
        let kinds: Vec<_> = planes.iter().map(|p| p.kind).collect();
        assert_eq!(kinds[0], PlaneKind::Ground, "{kinds:?}");
        let g = &planes[0];
        assert!(g.plane.normal.dot(&Vector3::z()) > 0.999);
        assert!((g.plane.d - 1.2).abs() < 0.02, "{}", g.plane.d);
        let ordinary: Vec<_> = planes
            .iter()
            .filter(|p| p.kind == PlaneKind::Ordinary)
            .collect();
        assert_eq!(ordinary.len(), 2, "{kinds:?}");
        let wall_x = ordinary
            .iter()
            .find(|p| p.plane.normal.x < -0.999)
            .expect("wall x = 3");
        assert!((wall_x.plane.d - 3.0).abs() < 0.02);
        let wall_y = ordinary
            .iter()
            .find(|p| p.plane.normal.y > 0.999)
            .expect("wall y = -2.5");
        assert!((wall_y.plane.d - 2.5).abs() < 0.02);
        for p in &planes {
            assert!(p.area > 1.0 && p.inliers.len() >= 200);
            assert!(p.plane.signed_distance(&p.centroid).abs() < 0.02);
        }
    }

    #[test]
    fn the_paper_acceptance_rule() {
        let p = ExtractorParams::default();
        assert!(!p.accepts(199, 1.0));
        assert!(!p.accepts(1000, 0.29));
        assert!(p.accepts(200, 1.0)); // 200 per m²
        assert!(!p.accepts(400, 5.0)); // 80 per m², fewer than 500
        assert!(p.accepts(500, 6.0)); // sparse but 500 points
    }
}
