//! The paper's detector: candidate points, multi-plane RANSAC with a
//! least-squares refit, convex-hull boundaries.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::candidates::dual_return_candidates;
use super::intensity_peak::{intensity_peak_candidates, IntensityPeakParams};
use super::{BoundedPlane, Detection, ReflectiveDetector, ReflectivePlane};
use crate::cloud::Frame;
use crate::geometry::cluster::euclidean_clusters;
use crate::geometry::fit::{ransac_plane, remove_positions, RansacParams};
use crate::geometry::{Plane, PlaneChart};
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

/// Detector thresholds (the paper's values are the defaults).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DetectorParams {
    /// Candidate source, also the detector's name.
    pub name: CandidateSource,
    /// Two returns of one beam further apart than this are a candidate, m.
    pub dual_gap: f64,
    /// RANSAC runs only with at least this many candidates left.
    pub min_candidates: usize,
    /// At most this many planes per frame.
    pub max_planes: usize,
    /// A plane needs more than this many inliers.
    pub min_inliers: usize,
    /// Reject planes whose normal has |z| above this (1.0 keeps all; the
    /// original Velodyne node used 0.5 to drop floors).
    pub max_abs_normal_z: f64,
    /// RANSAC settings.
    pub ransac: RansacParams,
    /// Intensity-peak search settings.
    pub intensity_peak: IntensityPeakParams,
    /// Inliers are grouped into clusters linked within this distance (m) in
    /// the plane; only clusters of at least `min_cluster` points bound the
    /// plane, so isolated edge echoes do not stretch the hull (0 disables:
    /// the paper's hull of all inliers).
    pub cluster_link: f64,
    /// Minimum cluster size kept for the boundary.
    pub min_cluster: usize,
    /// ... and of at least this share of the plane's inliers: a RANSAC plane
    /// collects every candidate within its band along the whole infinite
    /// plane, and stray groups far from the surface would stretch its hull
    /// (0: no relative bound).
    pub min_cluster_fraction: f64,
}

impl Default for DetectorParams {
    fn default() -> Self {
        Self {
            name: CandidateSource::DualReturn,
            dual_gap: 0.1,
            min_candidates: 300,
            max_planes: 3,
            min_inliers: 200,
            max_abs_normal_z: 1.0,
            ransac: RansacParams::default(),
            intensity_peak: IntensityPeakParams::default(),
            cluster_link: 0.0,
            min_cluster: 1,
            min_cluster_fraction: 0.0,
        }
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
            if plane.normal.z.abs() <= p.max_abs_normal_z {
                let support = self.boundary_support(frame, &plane, &inliers);
                if support.len() >= 3 {
                    let bounded = BoundedPlane::from_points(
                        plane,
                        support.iter().map(|&i| frame.points[i as usize].position()),
                    );
                    out.push(ReflectivePlane { bounded, inliers });
                }
            }
            remove_positions(&mut remaining, &fit.inliers);
        }
    }
}

impl CandidateRansacDetector {
    /// The inliers that bound the plane: all of them, or those in clusters
    /// of at least `min_cluster` points (see [`DetectorParams::cluster_link`]).
    fn boundary_support(&self, frame: &Frame, plane: &Plane, inliers: &[u32]) -> Vec<u32> {
        let p = &self.params;
        if !(p.cluster_link > 0.0) {
            return inliers.to_vec();
        }
        let chart = PlaneChart::of(plane);
        let uv: Vec<_> = inliers
            .iter()
            .map(|&i| chart.to_2d(&frame.points[i as usize].position()))
            .collect();
        let labels = euclidean_clusters(&uv, p.cluster_link);
        let mut sizes = vec![0usize; labels.iter().max().map_or(0, |m| m + 1)];
        for &l in &labels {
            sizes[l] += 1;
        }
        inliers
            .iter()
            .zip(&labels)
            .filter(|(_, &l)| {
                sizes[l] >= p.min_cluster
                    && sizes[l] as f64 >= p.min_cluster_fraction * inliers.len() as f64
            })
            .map(|(&i, _)| i)
            .collect()
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
            let peaks = intensity_peak_candidates(frame, scan, &self.sensor, &p.intensity_peak);
            let min = p.intensity_peak.min_inliers;
            self.fit_planes(frame, &peaks, min, min, &mut rng, &mut planes);
            candidates.extend(peaks);
            candidates.sort_unstable();
            candidates.dedup();
        }
        Detection { candidates, planes }
    }
}
