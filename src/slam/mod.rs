//! Reflection SLAM: scan-to-map tracking with ordinary, ground and
//! reflective planes as landmarks.
//!
//! The paper's "Global Map Update", made robust where it falls short:
//!
//! 0. [`deskew`]: a frame whose points carry their times is moved to its
//!    stamp with the motion model's velocity before anything else.
//! 1. [`motion`]: predict the pose (constant velocity over the elapsed time,
//!    bounded acceleration; [`clock`] gives the interval and reports gaps).
//! 2. Frame-to-frame registration ([`crate::registration`]) from the
//!    prediction gives the initial global pose; where it fails, a search
//!    over the heading ([`recovery`]) tries again.
//! 3. [`association`]: frame planes (moved to the world) against the map's
//!    landmarks by hull overlap (≥ 0.7 of the smaller hull) after normal and
//!    offset gates.
//! 4. RANSAC + Gauss–Newton against the map. Where the matched planes leave
//!    directions unconstrained (a corridor's axis), the information
//!    matrix's eigenvalues say so; the solution moves only in the
//!    observable subspace and keeps the prediction in the rest, and the
//!    frame's report names the unobservable directions.
//! 5. The observations update the map through the
//!    [`MapMerger`](crate::map::MapMerger); landmarks seen fewer than 3
//!    times within 30 frames are pruned (spurious or dynamic planes).
//!
//! [`Tracker`] runs these steps for one frame; the wiring over a sequence
//! (front end in parallel, tracking in order, classification with the
//! estimated poses) is [`crate::pipeline::slam`].

pub mod association;
pub mod clock;
pub mod deskew;
pub mod graph;
pub mod log;
pub mod loop_closure;
pub mod motion;
pub mod point_map;
pub mod recovery;
pub mod tracker;

pub use association::{associate, MapMatchParams};
pub use clock::{FrameClock, FrameTiming};
pub use log::{LandmarkObservation, PointsAnchor, TrackedFrame, TrackingLog};
pub use loop_closure::{LoopClosureParams, LoopConstraint};
pub use motion::{MotionModel, MotionModelName, MotionParams, MotionUpdate};
pub use point_map::{LocalPointMap, PointParams, ScanSamples};
pub use recovery::RecoveryParams;
pub use tracker::{FrameReport, LoopReport, SlamParams, Tracker};
