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

pub use plane_optimized::{run_plane_optimized, PlaneOptimizedOutput};
pub use sequence::Sequence;
pub use single_scan::run_single_scan;
pub use slam::{optimize_tracked, run_slam, track_sequence, SlamOutput, Tracked};
pub use timings::StageTimings;

use crate::classify::{Class, Rule, RuleTally};
use crate::eval::Confusion;

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
    /// Reflective planes detected in the frame.
    pub planes: usize,
    /// Candidate points found in the frame.
    pub candidates: usize,
}

/// A method's result over a sequence.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Per-frame results, in sequence order.
    pub frames: Vec<FrameOutput>,
    /// Time spent per stage.
    pub timings: StageTimings,
}

impl RunOutput {
    /// Confusion counts against the sequence's labels (`None` when the frames
    /// carry no labels).
    pub fn confusion(&self, sequence: &Sequence) -> Option<Confusion> {
        if !sequence.frames.iter().all(|f| f.has_labels) {
            return None;
        }
        let mut c = Confusion::default();
        for (f, out) in sequence.frames.iter().zip(&self.frames) {
            c.add_pairs(
                f.points
                    .iter()
                    .map(|p| p.label)
                    .zip(out.classes.iter().copied()),
            );
        }
        Some(c)
    }

    /// Points by the rule that decided them, their prediction and their
    /// label (label 0 for unlabelled frames).
    pub fn rule_tally(&self, sequence: &Sequence) -> RuleTally {
        let mut t = RuleTally::default();
        for (f, out) in sequence.frames.iter().zip(&self.frames) {
            t.add(f.points.iter().map(|p| p.label), &out.classes, &out.rules);
        }
        t
    }
}
