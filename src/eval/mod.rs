//! Scoring: the paper's classification metrics and the trajectory error.
//!
//! Classification ([`metrics`]), exactly as the paper defines it: ground
//! truth Normal = label 1, Glass = labels 2 and 3 (glass and mirror),
//! Reflection = 5, Obstacle = 6; labels 0 (unlabeled) and 4 (other
//! reflective) are ignored. A point predicted unclassified (0) is wrong for
//! every class's precision, recall and IoU, and counts as removed for the
//! reflection removal rate.
//!
//! Calibration ([`reliability`]): per bin of predicted confidence, the
//! share of points whose class is right, under the same scoring.
//!
//! Trajectories ([`trajectory`]): ATE after SE(3) alignment, RPE per metre
//! travelled, final drift.

pub mod metrics;
pub mod reliability;
pub mod trajectory;

pub use metrics::{ClassScores, Confusion, Metrics, EVAL_CLASSES};
pub use reliability::{Reliability, ReliabilityBin, ReliabilityReport};
pub use trajectory::{trajectory_error, umeyama, TrajectoryError};
