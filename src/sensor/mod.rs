//! Sensor models and the organized dual-return scan.
//!
//! A [`SensorModel`] describes a spinning LiDAR's beam pattern (ring
//! elevations, columns per revolution, range limits, return mode); it is read
//! from `configs/sensors/*.toml` (the built-in ones are embedded in the
//! binary). An [`OrganizedScan`] arranges a frame's points on the model's
//! ring × column grid, pairing both returns of each beam.

pub mod model;
pub mod scan;

pub use model::{IntensityScale, ReturnMode, SensorModel};
pub use scan::OrganizedScan;
