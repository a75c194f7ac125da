//! The single-scan pipeline: every frame on its own (pair, detect, classify).

use std::time::Instant;

use rayon::prelude::*;

use super::registry::{detector, frame_seed, single_scan_classifier};
use super::{FrameOutput, RunOutput, Sequence, StageTimings};
use crate::classify::FrameInput;
use crate::config::Config;
use crate::reflect::CandidateSource;
use crate::sensor::{OrganizedScan, SensorModel};
use crate::{Error, Result};

/// Check that the sequence can be processed by the configured detector:
/// no frame may be empty, and the dual-return detector needs second returns
/// in at least one frame (a single frame without any, e.g. facing only
/// walls, is normal in a long dual-return sequence; a sequence without any
/// is single-return data).
pub(crate) fn check_sequence(sequence: &Sequence, config: &Config) -> Result<()> {
    for (index, frame) in sequence.frames.iter().enumerate() {
        if frame.points.is_empty() {
            return Err(Error::Input(format!(
                "{}: frame has no points",
                sequence.path(index).display()
            )));
        }
    }
    if config.detector.name == CandidateSource::DualReturn
        && !sequence.is_empty()
        && sequence.frames.iter().all(|f| f.second_returns() == 0)
    {
        return Err(Error::Input(format!(
            "{}: frame has no second return (nor has any other frame); the dual-return \
             detector needs dual-return data (use [detector] name = \"intensity-peak\" for \
             single-return scans)",
            sequence.path(0).display()
        )));
    }
    Ok(())
}

/// Run the single-scan method over every frame (in parallel; the result does
/// not depend on the thread count).
pub fn run_single_scan(sequence: &Sequence, config: &Config) -> Result<RunOutput> {
    let wall = Instant::now();
    let sensor = SensorModel::resolve(&config.sensor)?;
    let detector = detector(config, &sensor);
    let classifier = single_scan_classifier(config);
    check_sequence(sequence, config)?;
    let results: Vec<(FrameOutput, StageTimings)> = sequence
        .frames
        .par_iter()
        .map(|frame| {
            let mut t = StageTimings::default();
            let start = Instant::now();
            let scan = OrganizedScan::build(frame, &sensor)?;
            t.add("pair", start.elapsed());
            let start = Instant::now();
            let detection = detector.detect(frame, &scan, frame_seed(config.seed, &frame.name));
            t.add("detect", start.elapsed());
            let start = Instant::now();
            let classes = classifier.classify(&FrameInput {
                frame,
                scan: &scan,
                sensor: &sensor,
                detection: &detection,
                pose: nalgebra::Isometry3::identity(),
                map_planes: &[],
                support: None,
            });
            t.add("classify", start.elapsed());
            t.frames = 1;
            Ok((
                FrameOutput {
                    name: frame.name.clone(),
                    classes,
                    planes: detection.planes.len(),
                    candidates: detection.candidates.len(),
                },
                t,
            ))
        })
        .collect::<Result<_>>()?;
    let mut timings = StageTimings::default();
    let mut frames = Vec::with_capacity(results.len());
    for (out, t) in results {
        timings.merge(&t);
        frames.push(out);
    }
    timings.wall = wall.elapsed();
    Ok(RunOutput { frames, timings })
}
