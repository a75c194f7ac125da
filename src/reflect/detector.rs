//! The paper's detector: candidate points, multi-plane RANSAC with a
//! least-squares refit, convex-hull boundaries.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::candidates::dual_return_candidates;
use super::intensity_peak::intensity_peak_candidates;
use super::{BoundedPlane, Detection, ReflectiveDetector, ReflectivePlane};
use crate::cloud::Frame;
use crate::geometry::fit::{ransac_plane, remove_positions, RansacParams};
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
        frame: &Frame,
        candidates: &[u32],
        min_candidates: usize,
        min_inliers: usize,
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
            if inliers.len() >= 3 {
                let bounded = BoundedPlane::from_points(
                    plane,
                    inliers.iter().map(|&i| frame.points[i as usize].position()),
                );
                out.push(ReflectivePlane { bounded, inliers });
            }
            remove_positions(&mut remaining, &fit.inliers);
        }
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
            self.fit_planes(
                frame,
                &dual,
                p.min_candidates,
                p.min_inliers,
                &mut rng,
                &mut planes,
            );
            candidates = dual;
        }
        if p.name != CandidateSource::DualReturn {
            // A sensor model without intensity-peak thresholds gives none.
            if let Some(peak) = &self.sensor.intensity_peak {
                let peaks = intensity_peak_candidates(frame, scan, &self.sensor, peak);
                let min = peak.min_inliers;
                self.fit_planes(frame, &peaks, min, min, &mut rng, &mut planes);
                candidates.extend(peaks);
            }
            candidates.sort_unstable();
            candidates.dedup();
        }
        Detection { candidates, planes }
    }
}
