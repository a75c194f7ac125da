//! Scoring predictions against 3DRef labels, exactly as the paper defines it.
//!
//! Ground truth: Normal = label 1, Glass = labels 2 and 3 (glass and mirror),
//! Reflection = 5, Obstacle = 6; labels 0 (unlabeled) and 4 (other
//! reflective) are ignored. A point predicted unclassified (0) is wrong for
//! every class's precision, recall and IoU, and counts as removed for the
//! reflection removal rate.

pub mod metrics;

pub use metrics::{ClassScores, Confusion, Metrics, EVAL_CLASSES};
