//! The single-scan pipeline: every frame on its own (pair, detect, classify).

use std::time::Instant;

use rayon::prelude::*;

use super::registry::{detector, frame_seed, single_scan_classifier};
use super::{FrameOutput, RunOutput, Sequence, StageTimings};
use crate::classify::FrameInput;
use crate::cloud::Frame;
use crate::config::Config;
use crate::reflect::{CandidateSource, Detection, ReflectiveDetector};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::{Error, Result};

/// Check that a frame can be processed by the configured detector: it has
/// points, and the sequence carries dual returns when the detector needs them.
pub(crate) fn check_frame(sequence: &Sequence, index: usize, config: &Config) -> Result<()> {
    let frame = &sequence.frames[index];
    if frame.points.is_empty() {
        return Err(Error::Input(format!(
            "{}: frame has no points",
            sequence.path(index).display()
        )));
    }
    // A frame without second returns is normal inside a dual-return sequence
    // (no glass in view); a sequence without any is not dual-return data.
    let dual_data = || {
        sequence
            .frames
            .iter()
            .any(|f| f.points.iter().any(|p| p.ret == 2))
    };
    if config.detector.name == CandidateSource::DualReturn
        && frame.second_returns() == 0
        && !dual_data()
    {
        let what = if sequence.len() == 1 {
            "the frame has no second return"
        } else {
            "no frame of the sequence has a second return"
        };
        return Err(Error::Input(format!(
            "{}: {what}; the dual-return detector needs dual-return data \
             (use [detector] name = \"intensity-peak\" for single-return scans)",
            sequence.path(index).display()
        )));
    }
    Ok(())
}

/// Pair a frame's returns on the sensor grid and detect its reflective
/// planes (the per-frame front of every pipeline), timing both stages.
pub(crate) fn organize_and_detect(
    frame: &Frame,
    sensor: &SensorModel,
    detector: &dyn ReflectiveDetector,
    seed: u64,
) -> Result<(OrganizedScan, Detection, StageTimings)> {
    let mut t = StageTimings::default();
    let start = Instant::now();
    let scan = OrganizedScan::build(frame, sensor)?;
    t.add("pair", start.elapsed());
    let start = Instant::now();
    let detection = detector.detect(frame, &scan, frame_seed(seed, &frame.name));
    t.add("detect", start.elapsed());
    Ok((scan, detection, t))
}

/// Run the single-scan method over every frame (in parallel; the result does
/// not depend on the thread count).
pub fn run_single_scan(sequence: &Sequence, config: &Config) -> Result<RunOutput> {
    let wall = Instant::now();
    let sensor = SensorModel::resolve(&config.sensor)?;
    let detector = detector(config, &sensor);
    let classifier = single_scan_classifier(config);
    for i in 0..sequence.len() {
        check_frame(sequence, i, config)?;
    }
    let bar = crate::progress::bar(sequence.len(), "classify");
    let results: Vec<(FrameOutput, StageTimings)> = sequence
        .frames
        .par_iter()
        .inspect(|_| bar.inc(1))
        .map(|frame| {
            let (scan, detection, mut t) =
                organize_and_detect(frame, &sensor, detector.as_ref(), config.seed)?;
            let start = Instant::now();
            let decisions = classifier.classify(&FrameInput {
                beam_hits: None,
                frame,
                scan: &scan,
                sensor: &sensor,
                detection: &detection,
                pose: nalgebra::Isometry3::identity(),
                map_planes: &[],
                support: None,
                space: None,
            });
            t.add("classify", start.elapsed());
            t.frames = 1;
            Ok((
                FrameOutput {
                    name: frame.name.clone(),
                    classes: decisions.classes,
                    rules: decisions.rules,
                    planes: detection.planes.len(),
                    candidates: detection.candidates.len(),
                },
                t,
            ))
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    let mut timings = StageTimings::default();
    let mut frames = Vec::with_capacity(results.len());
    for (out, t) in results {
        timings.merge(&t);
        frames.push(out);
    }
    timings.wall = wall.elapsed();
    Ok(RunOutput { frames, timings })
}
