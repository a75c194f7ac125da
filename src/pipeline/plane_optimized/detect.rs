//! Step 1: every frame's reflective planes, detected in the sensor frame
//! and carried to the world frame with the frame's pose. A frame's planes
//! (and two counts for its report) are all the pipeline keeps of it.

use std::time::Instant;

use nalgebra::Isometry3;

use crate::config::Config;
use crate::io::PlaneKind;
use crate::map::PlaneObservation;
use crate::pipeline::registry::{detector, frame_seed};
use crate::pipeline::single_scan::{check_dual_returns, check_points};
use crate::pipeline::{Sequence, StageTimings};
use crate::reflect::Detection;
use crate::sensor::SensorModel;
use crate::Result;

/// What the detection pass keeps of a frame: its reflective planes as
/// world-frame observations, and how many it found.
pub(super) struct FrameSummary {
    pub(super) observations: Vec<PlaneObservation>,
    pub(super) planes: usize,
    pub(super) candidates: usize,
}

/// Detect the reflective planes of every frame in one pass over the
/// sequence (in sequence order), and check that the frames have second
/// returns at all.
pub(super) fn detect_frames(
    sequence: &Sequence,
    config: &Config,
    sensor: &SensorModel,
    poses: &[Isometry3<f64>],
    timings: &mut StageTimings,
) -> Result<Vec<FrameSummary>> {
    let detector = detector(config, sensor);
    let mut summaries = Vec::with_capacity(sequence.len());
    let mut second_returns = 0;
    let reading = sequence.stream_all(
        "detect",
        |k, frame| {
            check_points(sequence, k, frame, sensor)?;
            let mut t = StageTimings::default();
            let scan = sequence.timed_scan(k, frame, sensor, &mut t)?;
            let start = Instant::now();
            let detection = detector.detect(frame, &scan, frame_seed(config.seed, &frame.name));
            t.add("detect", start.elapsed());
            let summary = FrameSummary {
                observations: observations(&detection, &poses[k], k),
                planes: detection.planes.len(),
                candidates: detection.candidates.len(),
            };
            Ok((summary, t))
        },
        |_, frame, (summary, t)| {
            timings.merge(&t);
            second_returns += frame.second_returns();
            summaries.push(summary);
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    check_dual_returns(sequence, second_returns, config)?;
    Ok(summaries)
}

/// A frame's reflective planes as world-frame observations.
pub fn observations(
    detection: &Detection,
    pose: &Isometry3<f64>,
    frame: usize,
) -> Vec<PlaneObservation> {
    detection
        .planes
        .iter()
        .map(|rp| PlaneObservation {
            kind: PlaneKind::Reflective,
            plane: rp.bounded.plane.transformed(pose),
            boundary: rp.bounded.boundary_3d().iter().map(|p| pose * p).collect(),
            frame,
        })
        .collect()
}
