//! Sensor models and the organized dual-return scan.
//!
//! A [`SensorModel`] describes a LiDAR's beam pattern (ring elevations,
//! columns per revolution, or a rosette; range limits, return mode); it is
//! read from `configs/sensors/*.toml` (the built-in ones are embedded in
//! the binary). An [`OrganizedScan`] arranges a frame's points on the
//! model's ring × column grid, pairing the returns of each beam (for a
//! rosette sensor: of each emission, on its grid of directions).

pub mod model;
pub mod rosette;
pub mod scan;

pub use model::{IntensityScale, ReturnMode, ScanPattern, SensorModel};
pub use rosette::{FieldOfView, Rosette};
pub use scan::OrganizedScan;
