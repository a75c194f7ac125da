//! Geometry in `f64` with the conventions of the design brief.
//!
//! - [`Plane`]: Hessian form `n·x + d = 0`, signed distance, transform,
//!   projection, Householder mirror and ray intersection.
//! - [`se3`]: the SE(3)/SO(3) exponential and logarithm and the Jacobians the
//!   back-end needs.
//! - [`PlaneChart`]: a 2-D coordinate chart on a plane, where boundaries live.
//! - [`ConvexPolygon`]: convex boundaries in a chart (hull, area,
//!   containment, intersection, union hull).
//! - [`fit`]: least-squares and RANSAC plane fitting.

pub mod chart;
pub mod cluster;
pub mod fastmath;
pub mod fit;
pub mod grid;
pub mod plane;
pub mod polygon;
pub mod se3;
pub mod voxel;

pub use chart::PlaneChart;
pub use plane::Plane;
pub use polygon::ConvexPolygon;
