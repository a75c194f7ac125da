//! Making results visible: a Foxglove MCAP recording of a run, PNG plots
//! and a Markdown report.
//!
//! | item | output |
//! |---|---|
//! | [`mcap::write_run_mcap`] | `run.mcap`: classified clouds, planes, poses (Foxglove) |
//! | [`plots`] | `topdown.png`, `trajectory.png`, `metrics.png` |
//! | [`report`] | `report.md` |

pub mod corner;
pub mod mcap;
pub mod plots;
pub mod report;

pub use self::mcap::{write_run_mcap, McapRecorder, McapRun, McapSummary};
