//! The paper's detector: candidate points, multi-plane RANSAC with a
//! least-squares refit, convex-hull boundaries.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::candidates::dual_return_candidates;
use super::intensity_peak::intensity_peak_candidates;
use super::{BoundedPlane, Detection, ReflectiveDetector, ReflectivePlane};
use crate::cloud::Frame;
use crate::geometry::fit::{ransac_plane, remove_positions, RansacParams};
use crate::geometry::Plane;
use crate::rng::SplitMix64;
use crate::sensor::{OrganizedScan, SensorModel};

/// Where candidate points come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CandidateSource {
    /// Beams whose two returns disagree (the paper's main cue).
    DualReturn,
    /// Intensity peaks along the horizontal ring (single-return sensors).
    IntensityPeak,
    /// Both cues.
    DualReturnAndIntensityPeak,
}

impl CandidateSource {
    /// The name the detector is selected by.
    pub fn name(self) -> &'static str {
        match self {
            CandidateSource::DualReturn => "dual-return",
            CandidateSource::IntensityPeak => "intensity-peak",
            CandidateSource::DualReturnAndIntensityPeak => "dual-return-and-intensity-peak",
        }
    }
}

/// Detector thresholds (`[detector]`; the paper's values in both
/// built-in configurations). The intensity-peak search's thresholds belong
/// to the sensor's intensity scale and ring layout: they are in its model
/// ([`SensorModel::intensity_peak`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorParams {
    /// Candidate source, also the detector's name.
    pub name: CandidateSource,
    /// Two returns of one beam further apart than this are a candidate, m.
    pub dual_gap: f64,
    /// RANSAC runs only with at least this many candidates left (points).
    pub min_candidates: usize,
    /// At most this many planes per frame.
    pub max_planes: usize,
    /// A plane needs more than this many inliers (points).
    pub min_inliers: usize,
    /// A plane is kept only where its candidates lie on a surface oriented
    /// as it: among the inliers whose neighbours in the scan span a surface,
    /// more must face within this angle of the plane's normal than
    /// directions drawn at random would (`1 - cos`), degrees. A plane fitted
    /// across the edge of a surface (one ring's glass echoes along a window
    /// with table edges at the same height: a "horizontal pane" that hides
    /// the floor) has its inliers' surfaces all across it. Absent: every
    /// RANSAC plane is kept (the paper).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_tolerance_deg: Option<f64>,
    /// RANSAC: the inlier distance (`[detector.ransac] distance`, m) is the
    /// only key; iterations and probability are [`RANSAC`]'s.
    #[serde(
        serialize_with = "crate::geometry::fit::serialize_distance",
        deserialize_with = "deserialize_ransac"
    )]
    pub ransac: RansacParams,
}

/// The detector's RANSAC but for the inlier distance (a key): at most 400
/// iterations, stopping once an outlier-free sample was drawn with
/// probability 0.9, and a least-squares refit (the paper's code).
pub const RANSAC: RansacParams = RansacParams {
    distance: 0.07,
    max_iterations: 400,
    probability: 0.9,
    refit: true,
};

fn deserialize_ransac<'de, D: serde::Deserializer<'de>>(d: D) -> Result<RansacParams, D::Error> {
    crate::geometry::fit::deserialize_distance(d, RANSAC)
}

impl Default for DetectorParams {
    /// `[detector]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("detector")
    }
}

/// What RANSAC needs per candidate source: the fewest candidates left to
/// run at all, and more inliers than this per plane.
#[derive(Debug, Clone, Copy)]
struct Minimums {
    candidates: usize,
    inliers: usize,
}

/// Candidates from the configured source, then up to `max_planes` RANSAC
/// planes (inliers removed after each), each bounded by its inliers' hull.
#[derive(Debug, Clone)]
pub struct CandidateRansacDetector {
    params: DetectorParams,
    sensor: SensorModel,
}

impl CandidateRansacDetector {
    /// A detector for frames of `sensor`.
    pub fn new(params: DetectorParams, sensor: SensorModel) -> Self {
        Self { params, sensor }
    }

    /// Fit up to `max_planes` planes to `candidates`, removing the inliers of
    /// each accepted plane before the next.
    fn fit_planes(
        &self,
        (frame, scan): (&Frame, &OrganizedScan),
        candidates: &[u32],
        Minimums {
            candidates: min_candidates,
            inliers: min_inliers,
        }: Minimums,
        rng: &mut SplitMix64,
        out: &mut Vec<ReflectivePlane>,
    ) {
        let p = &self.params;
        let mut remaining: Vec<u32> = candidates.to_vec();
        let origin = Point3::origin();
        while out.len() < p.max_planes && remaining.len() >= min_candidates.max(3) {
            let pts: Vec<Point3<f64>> = remaining
                .iter()
                .map(|&i| frame.points[i as usize].position())
                .collect();
            let Some(fit) = ransac_plane(&pts, &p.ransac, rng) else {
                break;
            };
            if fit.inliers.len() <= min_inliers {
                break;
            }
            let plane = fit.plane.facing(&origin);
            let inliers: Vec<u32> = fit.inliers.iter().map(|&k| remaining[k as usize]).collect();
            if inliers.len() >= 3 && self.lies_on_surface(frame, scan, &plane, &inliers) {
                let bounded = BoundedPlane::from_points(
                    plane,
                    inliers.iter().map(|&i| frame.points[i as usize].position()),
                );
                out.push(ReflectivePlane { bounded, inliers });
            }
            remove_positions(&mut remaining, &fit.inliers);
        }
    }

    /// Whether more of `inliers` lie on a surface oriented as `plane` than
    /// chance would give ([`DetectorParams::surface_tolerance_deg`]; always
    /// without it). Inliers whose neighbours span no surface do not count;
    /// when none does, nothing speaks against the plane.
    fn lies_on_surface(
        &self,
        frame: &Frame,
        scan: &OrganizedScan,
        plane: &Plane,
        inliers: &[u32],
    ) -> bool {
        let Some(tolerance) = self.params.surface_tolerance_deg else {
            return true;
        };
        let min_cos = tolerance.to_radians().cos();
        let (mut surfaces, mut aligned) = (0usize, 0usize);
        for &i in inliers {
            if let Some(faces) = scan.faces(frame, i as usize, &plane.normal, min_cos) {
                surfaces += 1;
                aligned += usize::from(faces);
            }
        }
        surfaces == 0 || aligned as f64 > (1.0 - min_cos) * surfaces as f64
    }
}

impl ReflectiveDetector for CandidateRansacDetector {
    fn name(&self) -> &'static str {
        self.params.name.name()
    }

    fn detect(&self, frame: &Frame, scan: &OrganizedScan, seed: u64) -> Detection {
        let p = &self.params;
        let mut rng = SplitMix64::new(seed);
        let mut planes = Vec::new();
        let mut candidates = Vec::new();
        if p.name != CandidateSource::IntensityPeak {
            let dual = dual_return_candidates(frame, scan, p.dual_gap);
            let min = Minimums {
                candidates: p.min_candidates,
                inliers: p.min_inliers,
            };
            self.fit_planes((frame, scan), &dual, min, &mut rng, &mut planes);
            candidates = dual;
        }
        if p.name != CandidateSource::DualReturn {
            // A sensor model without intensity-peak thresholds gives none.
            if let Some(peak) = &self.sensor.intensity_peak {
                let peaks = intensity_peak_candidates(frame, scan, &self.sensor, peak);
                let min = Minimums {
                    candidates: peak.min_inliers,
                    inliers: peak.min_inliers,
                };
                self.fit_planes((frame, scan), &peaks, min, &mut rng, &mut planes);
                candidates.extend(peaks);
            }
            candidates.sort_unstable();
            candidates.dedup();
        }
        Detection { candidates, planes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::scan::surface_frame;
    use nalgebra::Vector3;

    /// A wall 4 m ahead (x = 4) in every beam of the QT64, its scan, and
    /// the echoes of one ring on it straight ahead (|y| < 2 m): a line
    /// across the wall at nearly one height, as one ring's glass echoes lie
    /// along a window.
    fn ring_on_a_wall() -> (Frame, OrganizedScan, Vec<u32>, f64) {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = surface_frame(&sensor, "wall", |b| (b.x > 0.1).then(|| b * (4.0 / b.x)));
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let ring = 20;
        let inliers: Vec<u32> = (0..frame.points.len() as u32)
            .filter(|&i| {
                let p = &frame.points[i as usize];
                p.ring == ring && p.xyz[1].abs() < 2.0
            })
            .collect();
        let height = inliers
            .iter()
            .map(|&i| frame.points[i as usize].xyz[2] as f64)
            .sum::<f64>()
            / inliers.len() as f64;
        (frame, scan, inliers, height)
    }

    fn detector(surface_tolerance_deg: Option<f64>) -> CandidateRansacDetector {
        let params = DetectorParams {
            surface_tolerance_deg,
            ..DetectorParams::default()
        };
        CandidateRansacDetector::new(params, SensorModel::resolve("pandar_qt64").unwrap())
    }

    /// The plane at the ring's height cuts the wall its echoes lie on: not
    /// a pane. The wall's own plane holds them; the paper keeps both.
    #[test]
    fn a_plane_across_a_surface_is_no_pane() {
        let (frame, scan, inliers, height) = ring_on_a_wall();
        assert!(
            inliers.len() > 50 && height < -0.5,
            "{} {height}",
            inliers.len()
        );
        let origin = Point3::origin();
        let across = Plane::new(Vector3::z(), -height).unwrap().facing(&origin);
        let wall = Plane::new(Vector3::x(), -4.0).unwrap().facing(&origin);
        let ours = detector(Some(20.0));
        assert!(!ours.lies_on_surface(&frame, &scan, &across, &inliers));
        assert!(ours.lies_on_surface(&frame, &scan, &wall, &inliers));
        let paper = detector(None);
        assert!(paper.lies_on_surface(&frame, &scan, &across, &inliers));
    }

    /// The default configuration checks the surface; the paper's does not.
    #[test]
    fn the_surface_check_is_ours_not_the_papers() {
        assert_eq!(DetectorParams::default().surface_tolerance_deg, Some(20.0));
        let paper = crate::config::Config::resolve("paper").unwrap();
        assert_eq!(paper.detector.surface_tolerance_deg, None);
    }
}
