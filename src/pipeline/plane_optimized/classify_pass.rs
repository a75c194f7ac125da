//! Step 5: every frame classified against the map, with what the keyframes
//! saw, in one pass over the sequence; each frame's classes go to the sink
//! in sequence order and are scored against its labels.

use std::time::Instant;

use super::detect::FrameSummary;
use super::keyframes::{FrameViews, Seen};
use crate::classify::{Classifier, FrameInput};
use crate::pipeline::{FrameOutput, FrameSink, RunScore, StageTimings};
use crate::Result;

/// Classify every frame of `views.sequence` against `seen.planes`, handing
/// each frame's output to `sink`; `summaries` give each frame's detection
/// counts for its report.
pub(super) fn classify_frames(
    views: &FrameViews<'_>,
    seen: &Seen,
    summaries: &[FrameSummary],
    sink: &mut dyn FrameSink,
    timings: &mut StageTimings,
) -> Result<RunScore> {
    let FrameViews {
        sequence,
        sensor,
        classifier,
        poses,
    } = *views;
    sink.begin(&seen.planes)?;
    let mut score = RunScore::default();
    let reading = sequence.stream_all(
        "classify",
        |k, frame| {
            let mut t = StageTimings::default();
            let scan = sequence.timed_scan(k, frame, sensor, &mut t)?;
            let start = Instant::now();
            let decisions = classifier.classify(&FrameInput {
                support: seen.support.as_ref(),
                space: seen.space.as_ref(),
                ..views.input(k, frame, &scan, &seen.planes)
            });
            t.add("classify", start.elapsed());
            Ok((decisions, t))
        },
        |k, frame, (decisions, t)| {
            timings.merge(&t);
            let output = FrameOutput {
                name: frame.name.clone(),
                classes: decisions.classes,
                rules: decisions.rules,
                confidence: decisions.confidence,
                planes: summaries[k].planes,
                candidates: summaries[k].candidates,
                set_aside: sequence.set_aside(k, frame)?,
            };
            let start = Instant::now();
            score.add(sequence.path(k), frame, &output);
            timings.add("score", start.elapsed());
            let start = Instant::now();
            sink.frame(k, frame, Some(&poses[k]), output)?;
            timings.add("write outputs", start.elapsed());
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    Ok(score)
}
