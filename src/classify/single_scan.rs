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

/// Parameters of the single-scan classifier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SingleScanParams {
    /// Boundary model.
    pub boundary: BoundaryModel,
    /// Rings added above and below the window.
    pub window_ring_pad: usize,
    /// Windows narrower than this (degrees of azimuth) cover the whole
    /// revolution (Zhao 2020: 81 columns of 0.6 degrees).
    pub window_min_deg: f64,
    /// Hull growth, metres (hull boundary only).
    pub hull_margin: f64,
    /// The decision thresholds and switches.
    pub decision: DecisionParams,
}

impl Default for SingleScanParams {
    fn default() -> Self {
        Self {
            boundary: BoundaryModel::Window,
            window_ring_pad: 1,
            window_min_deg: 48.6,
            hull_margin: 0.0,
            decision: DecisionParams::default(),
        }
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
