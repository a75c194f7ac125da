//! The single-scan method (Zhao, Yang and Schwertfeger 2020) that the paper
//! compares against, with the original code's bugs fixed: planes come from
//! the frame's own detection, pairing is in the sensor frame, the window
//! wraps around the azimuth seam, last-return points in front of the glass
//! are kept as Normal, and every detected plane (not only the first) bounds
//! beams.

use serde::{Deserialize, Serialize};

use super::boundary::{BeamPlanes, Window};
use super::decide::{decide, DecisionParams};
use super::{Classifier, Decisions, FrameInput};
use crate::reflect::BoundedPlane;

/// How a detected plane's extent is bounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryModel {
    /// Zhao 2020: a ring × column window around the plane's inliers.
    Window,
    /// The convex hull of the plane's inliers (the paper's boundary).
    Hull,
}

/// Parameters of the single-scan classifier: Zhao 2020's method, its
/// constants in code ([`DecisionParams::ZHAO2020`], [`WINDOW_RING_PAD`],
/// [`WINDOW_MIN_DEG`]); the configuration chooses the boundary and the
/// free-space neighbourhood (`[single_scan]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "SingleScanKeys", into = "SingleScanKeys")]
pub struct SingleScanParams {
    /// Boundary model.
    pub boundary: BoundaryModel,
    /// Rings added above and below the window.
    pub window_ring_pad: usize,
    /// Windows narrower than this (degrees of azimuth) cover the whole
    /// revolution.
    pub window_min_deg: f64,
    /// Hull growth, metres (hull boundary only).
    pub hull_margin: f64,
    /// The decision thresholds and switches.
    pub decision: DecisionParams,
}

/// Zhao 2020's window: one ring added above and below the inliers' rings.
pub const WINDOW_RING_PAD: usize = 1;
/// Zhao 2020's window: narrower than 48.6 degrees of azimuth (81 columns of
/// 0.6 degrees) it covers the whole revolution.
pub const WINDOW_MIN_DEG: f64 = 48.6;

/// The keys of `[single_scan]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SingleScanKeys {
    /// Boundary model: `window` (Zhao 2020) or `hull` (the paper's).
    boundary: BoundaryModel,
    /// Rings and columns around the mirrored point's cell that must all show
    /// free space, cells: 0 the cell alone (Zhao 2020), 1 the 3 x 3 block
    /// (robust to the ring and column quantisation of the mirrored
    /// direction).
    free_space_neighbourhood: usize,
}

impl From<SingleScanKeys> for SingleScanParams {
    fn from(k: SingleScanKeys) -> Self {
        Self {
            boundary: k.boundary,
            window_ring_pad: WINDOW_RING_PAD,
            window_min_deg: WINDOW_MIN_DEG,
            hull_margin: 0.0,
            decision: DecisionParams {
                free_space_neighbourhood: k.free_space_neighbourhood,
                ..DecisionParams::ZHAO2020
            },
        }
    }
}

impl From<SingleScanParams> for SingleScanKeys {
    fn from(p: SingleScanParams) -> Self {
        Self {
            boundary: p.boundary,
            free_space_neighbourhood: p.decision.free_space_neighbourhood,
        }
    }
}

impl Default for SingleScanParams {
    /// `[single_scan]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("single_scan")
    }
}

/// Classifies a frame against the reflective planes detected in it.
#[derive(Debug, Clone)]
pub struct SingleScanClassifier {
    params: SingleScanParams,
}

impl SingleScanClassifier {
    /// A classifier with the given parameters.
    pub fn new(params: SingleScanParams) -> Self {
        Self { params }
    }
}

impl Classifier for SingleScanClassifier {
    fn name(&self) -> &'static str {
        "single-scan"
    }

    fn classify(&self, input: &FrameInput<'_>) -> Decisions {
        let p = &self.params;
        let planes: Vec<BoundedPlane> = input
            .detection
            .planes
            .iter()
            .map(|rp| rp.bounded.clone())
            .collect();
        let beams = match p.boundary {
            BoundaryModel::Hull => BeamPlanes::hulls(&planes, p.hull_margin),
            BoundaryModel::Window => {
                let min_cols = (p.window_min_deg / input.sensor.column_step_deg()).round() as usize;
                let windows = input
                    .detection
                    .planes
                    .iter()
                    .map(|rp| {
                        Window::around(input.scan, &rp.inliers, p.window_ring_pad, min_cols)
                            .unwrap_or(Window {
                                ring_lo: 0,
                                ring_hi: 0,
                                col_start: 0,
                                col_len: 0,
                            })
                    })
                    .collect();
                BeamPlanes::windows(&planes, windows)
            }
        };
        decide(
            input.frame,
            input.scan,
            input.sensor,
            &beams,
            &p.decision,
            None,
        )
    }
}
