//! Wiring: loading a sequence and running a method over it.
//!
//! The stages themselves take plain parameter structs; only this layer reads
//! the [`Config`](crate::config::Config) and picks implementations by name.

pub mod plane_optimized;
pub mod registry;
pub mod sequence;
pub mod single_scan;
pub mod slam;
pub mod timings;

pub use plane_optimized::{run_plane_optimized, run_plane_optimized_into, PlaneOptimizedOutput};
pub use sequence::{stream_window, Sequence};
pub use single_scan::{run_single_scan, run_single_scan_into};
pub use slam::{
    optimize_tracked, optimize_tracked_with, run_slam, track_sequence, MakeBackend, SlamOutput,
    Tracked,
};
pub use timings::StageTimings;

use std::path::Path;

use nalgebra::Isometry3;

use crate::classify::{Class, Rule, RuleTally};
use crate::cloud::{Frame, SetAside};
use crate::eval::{Confusion, Reliability};
use crate::reflect::BoundedPlane;
use crate::Result;

/// One frame's result.
#[derive(Debug, Clone)]
pub struct FrameOutput {
    /// Frame name (file stem).
    pub name: String,
    /// One class per point, input order.
    pub classes: Vec<Class>,
    /// The rule that decided each point's class (empty where the method
    /// does not say).
    pub rules: Vec<Rule>,
    /// The posterior probability of each point's class (empty where the
    /// method does not say; see [`Decisions::confidence`](crate::classify::Decisions)).
    pub confidence: Vec<f32>,
    /// Reflective planes detected in the frame.
    pub planes: usize,
    /// Candidate points found in the frame.
    pub candidates: usize,
    /// Where the input points its reader set aside (not finite, or at the
    /// origin; not in `classes`) were: outputs are written per input
    /// point, label 0 there ([`FrameOutput::input_class_ids`]).
    pub set_aside: SetAside,
}

impl FrameOutput {
    /// The class id of every input point, in input order: the classes
    /// with 0 (unclassified) at each point set aside. What a `.label`
    /// file holds.
    pub fn input_class_ids(&self) -> Vec<u8> {
        let ids: Vec<u8> = self.classes.iter().map(|c| c.id()).collect();
        self.set_aside.scatter(&ids, Class::Unclassified.id())
    }

    /// The id of the rule that decided every input point, in input order
    /// (0, undecided, at each point set aside). What a `.rule` file holds.
    pub fn input_rule_ids(&self) -> Vec<u8> {
        let ids: Vec<u8> = self.rules.iter().map(|r| r.id()).collect();
        self.set_aside.scatter(&ids, Rule::Undecided.id())
    }

    /// The confidence of every input point's class, in input order (0 at
    /// each point set aside, whose class is unclassified). What a `.prob`
    /// file holds; empty when the method does not say
    /// ([`confidence`](Self::confidence) is empty).
    pub fn input_confidence(&self) -> Vec<f32> {
        if self.confidence.is_empty() {
            return Vec::new();
        }
        self.set_aside.scatter(&self.confidence, 0.0)
    }
}

/// A method's result over a sequence.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Per-frame results, in sequence order, when collected (empty when
    /// the frames were handed to a [`FrameSink`] instead).
    pub frames: Vec<FrameOutput>,
    /// Confusion counts against the labels (`None` when a frame carries
    /// no labels).
    pub confusion: Option<Confusion>,
    /// The calibration of the confidences against the labels (`None` when
    /// a frame carries no labels, or no frame says a confidence).
    pub reliability: Option<Reliability>,
    /// Points by the rule that decided them, their prediction and their
    /// label (label 0 for unlabelled frames).
    pub rules: RuleTally,
    /// Time spent per stage.
    pub timings: StageTimings,
    /// Input points dropped over the run because a coordinate or the
    /// intensity was not finite (the sum of
    /// [`Frame::dropped_non_finite`]): reported in `metrics.json`, so a run
    /// on data with holes says how many points it never saw.
    pub dropped_non_finite: usize,
}

/// Receives each frame's result as a run produces it, in sequence order:
/// a long sequence's classes are written or summarised as they come, never
/// held all at once.
pub trait FrameSink {
    /// Called once before the first frame with the reflective planes
    /// (world frame) the frames are classified against; none for methods
    /// without a map.
    fn begin(&mut self, _planes: &[BoundedPlane]) -> Result<()> {
        Ok(())
    }

    /// One frame's result. `frame` is the frame as read, `pose` its
    /// `T_world_sensor` when known.
    fn frame(
        &mut self,
        index: usize,
        frame: &Frame,
        pose: Option<&Isometry3<f64>>,
        output: FrameOutput,
    ) -> Result<()>;
}

/// Collecting sink: keeps every frame's result (short sequences, tests,
/// tables).
impl FrameSink for Vec<FrameOutput> {
    fn frame(
        &mut self,
        _index: usize,
        _frame: &Frame,
        _pose: Option<&Isometry3<f64>>,
        output: FrameOutput,
    ) -> Result<()> {
        self.push(output);
        Ok(())
    }
}

/// A sink that keeps nothing: the run's scores are all that is wanted.
#[derive(Debug, Clone, Copy, Default)]
pub struct Discard;

impl FrameSink for Discard {
    fn frame(
        &mut self,
        _index: usize,
        _frame: &Frame,
        _pose: Option<&Isometry3<f64>>,
        _output: FrameOutput,
    ) -> Result<()> {
        Ok(())
    }
}

/// The scores a run accumulates frame by frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct RunScore {
    confusion: Confusion,
    /// Filled from the frames that say a confidence; `None` until one does.
    reliability: Option<Reliability>,
    rules: RuleTally,
    unlabelled: bool,
    dropped_non_finite: usize,
    /// Frames with labels seen so far.
    labelled_frames: usize,
    /// The first frame without labels, when any.
    first_unlabelled: Option<String>,
}

impl RunScore {
    /// Count one frame's classes against its labels, and the points its
    /// reader dropped as non-finite (with a warning naming `path`, the
    /// frame's source, when there are any). Called once per frame.
    pub(crate) fn add(&mut self, path: &Path, frame: &Frame, output: &FrameOutput) {
        if frame.dropped_non_finite > 0 {
            tracing::warn!(
                "{}: dropped {} points with a non-finite coordinate or intensity (NaN or inf)",
                path.display(),
                frame.dropped_non_finite
            );
            self.dropped_non_finite += frame.dropped_non_finite;
        }
        self.unlabelled |= !frame.has_labels;
        if frame.has_labels {
            self.labelled_frames += 1;
        } else if self.first_unlabelled.is_none() {
            self.first_unlabelled = Some(path.display().to_string());
        }
        let labels = frame.points.iter().map(|p| p.label);
        self.confusion
            .add_pairs(labels.clone().zip(output.classes.iter().copied()));
        if !output.confidence.is_empty() {
            // Set-aside points are unclassified: never binned.
            self.reliability.get_or_insert_default().add_points(
                labels
                    .clone()
                    .zip(output.classes.iter().copied())
                    .zip(output.confidence.iter().copied())
                    .map(|((l, c), p)| (l, c, p)),
            );
        }
        self.rules.add(labels, &output.classes, &output.rules);
        if !output.set_aside.is_empty() {
            // Scored against every input point: one set aside is
            // unclassified, decided by no rule.
            let aside = &output.set_aside;
            let classes = vec![Class::Unclassified; aside.len()];
            self.confusion
                .add_pairs(aside.labels.iter().copied().zip(classes.iter().copied()));
            let rules = vec![Rule::Undecided; aside.len()];
            self.rules
                .add(aside.labels.iter().copied(), &classes, &rules);
        }
    }

    /// The run's output with these scores.
    pub(crate) fn finish(self, frames: Vec<FrameOutput>, timings: StageTimings) -> RunOutput {
        if let (Some(first), true) = (&self.first_unlabelled, self.labelled_frames > 0) {
            // One frame without labels leaves the whole run unscored: say
            // so, rather than print predicted counts as if none had any.
            tracing::warn!(
                "{first} has no 'label' property while {} other frames have one: the run is not scored",
                self.labelled_frames
            );
        }
        RunOutput {
            frames,
            confusion: (!self.unlabelled).then_some(self.confusion),
            reliability: self.reliability.filter(|_| !self.unlabelled),
            rules: self.rules,
            timings,
            dropped_non_finite: self.dropped_non_finite,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Point;

    fn output(classes: Vec<Class>, confidence: Vec<f32>, aside: SetAside) -> FrameOutput {
        FrameOutput {
            name: "f".into(),
            rules: Vec::new(),
            classes,
            confidence,
            planes: 0,
            candidates: 0,
            set_aside: aside,
        }
    }

    /// One confidence per input point, 0 where a point was set aside; none
    /// at all when the method gives none.
    #[test]
    fn input_confidence_keeps_a_slot_for_every_input_point() {
        let aside = SetAside {
            positions: vec![0, 3],
            labels: vec![1, 5],
        };
        let out = output(
            vec![Class::Normal, Class::Glass, Class::Reflection],
            vec![0.5, 0.75, 1.0],
            aside.clone(),
        );
        assert_eq!(out.input_confidence(), vec![0.0, 0.5, 0.75, 0.0, 1.0]);
        assert_eq!(out.input_class_ids(), vec![0, 1, 2, 0, 5]);
        let silent = output(vec![Class::Normal; 3], Vec::new(), aside);
        assert!(silent.input_confidence().is_empty());
    }

    /// The run's reliability counts the frames that give confidences, under
    /// the confusion's scoring; set-aside points are never binned; a run
    /// whose frames give none has no reliability.
    #[test]
    fn the_run_score_bins_the_confidences() {
        let frame = |labels: &[u8]| Frame {
            name: "f".into(),
            stamp: 0.0,
            points: labels
                .iter()
                .map(|&label| Point {
                    xyz: [1.0, 0.0, 0.0],
                    label,
                    ..Default::default()
                })
                .collect(),
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        };
        let path = Path::new("f.ply");
        let mut score = RunScore::default();
        // Mirror (3) predicted glass: right; normal predicted obstacle:
        // wrong; an ignored label; an unclassified point.
        let a = frame(&[3, 1, 4, 1]);
        let aside = SetAside {
            positions: vec![1],
            labels: vec![1],
        };
        let classes = vec![
            Class::Glass,
            Class::Obstacle,
            Class::Normal,
            Class::Unclassified,
        ];
        score.add(
            path,
            &a,
            &output(classes.clone(), vec![0.95, 0.35, 0.95, 0.5], aside),
        );
        // A frame without confidences adds nothing to the reliability.
        score.add(path, &a, &output(classes, Vec::new(), SetAside::default()));
        let run = score.finish(Vec::new(), StageTimings::default());
        let r = run.reliability.expect("confidences were given").report();
        assert_eq!(r.points, 2);
        assert_eq!((r.bins[9].points, r.bins[9].correct), (1, 1));
        assert_eq!((r.bins[3].points, r.bins[3].correct), (1, 0));
        assert_eq!(r.confident_points, 1);
        assert!((r.confident_accuracy - 1.0).abs() < 1e-12);
        // The confusion saw every point of both frames, set-aside included.
        assert_eq!(
            run.confusion
                .unwrap()
                .by_label
                .iter()
                .flatten()
                .sum::<u64>(),
            9
        );

        let mut silent = RunScore::default();
        silent.add(
            path,
            &a,
            &output(vec![Class::Normal; 4], Vec::new(), SetAside::default()),
        );
        assert!(silent
            .finish(Vec::new(), StageTimings::default())
            .reliability
            .is_none());
    }
}
