//! Making results visible: a Foxglove MCAP recording of a run, PNG plots
//! and a Markdown report.
//!
//! | item | output |
//! |---|---|
//! | [`mcap::write_run_mcap`] | `run.mcap`: classified clouds, planes, poses (Foxglove) |
//! | [`topdown`] | `topdown.png`: the classified map from above, a height slice |
//! | [`plots`] | `trajectory.png` (estimate and ground truth), `metrics.png` |
//! | [`bench`](mod@bench) | `bench.png`: the benchmark's seeds per family |
//! | [`corner`] | the around-the-corner figure (of `specular-reproduce`) |
//! | [`report`] | `report.md` |
//! | [`params`] | what the outputs are made of (`[output]` in the configuration) |

pub mod bench;
pub mod corner;
pub mod floor;
pub mod legend;
pub mod mcap;
pub mod params;
pub mod plots;
pub mod report;
pub mod topdown;

pub use self::mcap::{write_run_mcap, McapRecorder, McapRun, McapSummary};
pub use params::OutputParams;
