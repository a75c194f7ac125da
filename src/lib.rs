//! # specular
//!
//! Reflection-aware plane SLAM on dual-return LiDAR.
//!
//! Glass and mirrors break LiDAR: a beam reports the glass, the object behind
//! it, or a ghost reflected into a place where nothing is. specular finds the
//! reflective planes from dual returns, fuses them into a plane map, classifies
//! every point (Normal, reflective surface, Reflection, Obstacle behind glass)
//! and mirrors reflections back to their true place.
//!
//! The crate is organised as the method is:
//!
//! | module | role |
//! |---|---|
//! | [`geometry`] | planes, SE(3), convex polygons in a plane chart, plane fitting |
//! | [`sensor`] | sensor models (rings, columns) and the organized dual-return scan |
//! | [`io`] | 3DRef PLY frames, TUM poses, prediction labels, frame/pose matching |
//! | [`reflect`] | reflective-plane detection in one scan (`ReflectiveDetector`) |
//! | [`frontend`] | ordinary and ground planes of one scan (`PlaneExtractor`) |
//! | [`backend`] | sparse pose-plane factor graph: Gauss–Newton / Levenberg–Marquardt on faer, the paper's average |
//! | [`registration`] | plane matching, mismatch rejection (`MismatchRejector`), closed form and Gauss–Newton |
//! | [`map`] | the global plane map: landmarks, merging, transparency evidence, panes |
//! | [`slam`] | scan-to-map tracking, degeneracy handling, map update |
//! | [`classify`] | per-point classification (`Classifier`) and mirror-back |
//! | [`eval`] | the paper's metrics: precision, recall, IoU, removal rate |
//! | [`bench`](mod@bench) | the held-out benchmark: both pipelines over seeds of every scene family |
//! | [`pipeline`] | wiring: runs a method over a sequence of frames |
//! | [`sim`] | dual-return LiDAR simulator with glass and mirrors (labelled sequences with exact truth) |
//! | [`config`] | the TOML configuration, the single source of defaults |
//! | [`viz`] | Foxglove MCAP recordings, PNG plots, Markdown report |
//! | [`logging`], [`progress`] | what a command shows on stderr: its log and progress bars |
//!
//! The paper's experiments beside its published tables are not in this
//! crate: they use it from the workspace member `specular-paper`
//! (`paper/reproduce/`, the `specular-reproduce` command).
//!
//! Conventions (kept everywhere): a plane is `n·x + d = 0` with `|n| = 1`;
//! in a sensor frame `d > 0` (the sensor is on the positive side). Poses are
//! `T_world_sensor`. Geometry is `f64`; bulk point storage is `f32`.

// `!(x > 0.0)` is used deliberately: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod backend;
pub mod bench;
pub mod classify;
pub mod cloud;
pub mod config;
pub mod error;
pub mod eval;
pub mod frontend;
pub mod geometry;
pub mod io;
pub mod logging;
pub mod map;
pub mod pipeline;
pub mod progress;
pub mod reflect;
pub mod registration;
pub mod rng;
pub mod sensor;
pub mod sim;
pub mod slam;
pub mod viz;

pub use error::{Error, Result};

/// The version of specular, written into every run's `metrics.json` and
/// `report.md` so a result can be traced to the code that made it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit specular was built from ("unknown" outside a git
/// checkout); see [`VERSION`].
pub const GIT_COMMIT: &str = env!("SPECULAR_GIT_COMMIT");

/// `{"version": .., "commit": ..}`: what produced a result, for the
/// `specular` key of `metrics.json`.
pub fn provenance() -> serde_json::Value {
    serde_json::json!({ "version": VERSION, "commit": GIT_COMMIT })
}
