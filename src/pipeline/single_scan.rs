//! The single-scan pipeline: every frame on its own (pair, detect, classify).

use std::time::Instant;

use super::registry::{detector, frame_seed, single_scan_classifier};
use super::{FrameOutput, FrameSink, RunOutput, RunScore, Sequence, StageTimings};
use crate::classify::FrameInput;
use crate::cloud::Frame;
use crate::config::Config;
use crate::reflect::{CandidateSource, Detection, ReflectiveDetector};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::{Error, Result};

/// Check that a frame can be processed: it has points (the error names
/// the file the frame came from). A frame whose every point was set aside
/// (all NaN, say: a sensor that saw nothing) is not an error: it has
/// nothing to classify and its labels are all 0; nor is an empty frame of
/// a sensor with a limited field of view (a Livox facing open space or a
/// wall nearer than its minimum range sees nothing).
pub(crate) fn check_points(
    sequence: &Sequence,
    index: usize,
    frame: &Frame,
    sensor: &SensorModel,
) -> Result<()> {
    let may_see_nothing = frame.dropped_non_finite > 0 || sensor.field_of_view().is_some();
    if frame.points.is_empty() && !may_see_nothing {
        return Err(Error::Input(format!(
            "{}: frame has no points",
            sequence.path(index).display()
        )));
    }
    Ok(())
}

/// Check, after a pass over the whole sequence that counted
/// `second_returns`, that the sequence carries dual returns when the
/// configured detector needs them. A frame without second returns is
/// normal inside a dual-return sequence (no glass in view); a sequence
/// without any is not dual-return data.
pub(crate) fn check_dual_returns(
    sequence: &Sequence,
    second_returns: usize,
    config: &Config,
) -> Result<()> {
    if config.detector.name != CandidateSource::DualReturn || second_returns > 0 {
        return Ok(());
    }
    let what = if sequence.len() == 1 {
        "the frame has no second return"
    } else {
        "no frame of the sequence has a second return"
    };
    Err(Error::Input(format!(
        "{}: {what}; the dual-return detector needs dual-return data \
         (use [detector] name = \"intensity-peak\" for single-return scans)",
        sequence.path(0).display()
    )))
}

/// Pair a frame's returns on the sensor grid and detect its reflective
/// planes (the per-frame front of every pipeline), timing both stages.
/// The grid cells come from `measured`, the frame as measured (the same
/// points in the same order): a deskewed frame's points have moved off
/// their beams' directions, and the returns of one beam, moved alike but
/// at different ranges, would no longer share a cell.
pub(crate) fn organize_and_detect(
    frame: &Frame,
    measured: &Frame,
    sensor: &SensorModel,
    detector: &dyn ReflectiveDetector,
    seed: u64,
) -> Result<(OrganizedScan, Detection, StageTimings)> {
    let mut t = StageTimings::default();
    let start = Instant::now();
    let scan = OrganizedScan::build(measured, sensor)?;
    t.add("pair", start.elapsed());
    let start = Instant::now();
    let detection = detector.detect(frame, &scan, frame_seed(seed, &frame.name));
    t.add("detect", start.elapsed());
    Ok((scan, detection, t))
}

/// Run the single-scan method over every frame and keep the results.
pub fn run_single_scan(sequence: &Sequence, config: &Config) -> Result<RunOutput> {
    let mut frames = Vec::with_capacity(sequence.len());
    let mut out = run_single_scan_into(sequence, config, &mut frames)?;
    out.frames = frames;
    Ok(out)
}

/// Run the single-scan method over every frame (in parallel, a window at a
/// time; the result does not depend on the thread count), handing each
/// frame's result to `sink` in sequence order. The returned output holds
/// the scores and timings, no frames.
pub fn run_single_scan_into(
    sequence: &Sequence,
    config: &Config,
    sink: &mut dyn FrameSink,
) -> Result<RunOutput> {
    let wall = Instant::now();
    let sensor = sequence.sensor(config)?;
    let detector = detector(config, &sensor);
    let classifier = single_scan_classifier(config);
    let mut timings = StageTimings::default();
    let mut score = RunScore::default();
    let mut second_returns = 0;
    sink.begin(&[])?;
    let work = |k: usize, frame: &Frame| {
        check_points(sequence, k, frame, &sensor)?;
        let measured = sequence.as_measured(k, frame)?;
        let (scan, detection, mut t) =
            organize_and_detect(frame, &measured, &sensor, detector.as_ref(), config.seed)?;
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
        let output = FrameOutput {
            name: frame.name.clone(),
            classes: decisions.classes,
            rules: decisions.rules,
            confidence: decisions.confidence,
            planes: detection.planes.len(),
            candidates: detection.candidates.len(),
            set_aside: sequence.set_aside(k, frame)?,
        };
        Ok((output, t, frame.second_returns()))
    };
    let reading = sequence.stream_all("classify", work, |k, frame, (output, t, seconds)| {
        timings.merge(&t);
        second_returns += seconds;
        let start = Instant::now();
        score.add(sequence.path(k), frame, &output);
        timings.add("score", start.elapsed());
        let pose = sequence.poses.as_ref().map(|p| &p[k]);
        let start = Instant::now();
        sink.frame(k, frame, pose, output)?;
        timings.add("write outputs", start.elapsed());
        Ok(())
    })?;
    timings.add_reading(reading);
    check_dual_returns(sequence, second_returns, config)?;
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    Ok(score.finish(Vec::new(), timings))
}
