//! What tracking hands to the back-end: the frames' poses and odometry, and
//! every plane observation with the landmark it was fused into.
//!
//! The tracker's map keeps only the fused landmark; a joint optimisation
//! needs the individual measurements (GTSAM's factor graph is built from
//! them), so the tracker logs them as it goes.

use nalgebra::{Isometry3, Matrix3, Point3, Vector6};

use crate::frontend::FramePlane;
use crate::geometry::Plane;
use crate::io::PlaneKind;

/// One tracked frame.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackedFrame {
    /// The tracked pose `T_world_sensor`.
    pub pose: Isometry3<f64>,
    /// The frame-to-frame registration `T_previous_current`, when it
    /// succeeded (a relative-pose measurement independent of the map).
    pub odometry: Option<Isometry3<f64>>,
    /// The directions of `odometry` (orthonormal tangent vectors `(ρ, φ)`,
    /// this frame's sensor frame) that nothing measured: the
    /// frame-to-frame registration left them free and the points did not
    /// fix them, so there the odometry is the motion model's prediction.
    pub odometry_free: Vec<Vector6<f64>>,
    /// Whether the frame is a keyframe: a pose of the batch back-end's
    /// graph, with its plane observations logged.
    pub keyframe: bool,
    /// Where the points fixed directions the planes left free: the frame
    /// the local point map's matched points came from (their median) and
    /// the fixed directions (sensor-frame tangent vectors). Along them the
    /// tracked pose is a measurement relative to that frame.
    pub points_anchor: Option<PointsAnchor>,
}

/// The point term's measurement of a frame: along `directions` its pose is
/// known relative to frame `frame` (the frame whose samples it was
/// registered against).
#[derive(Debug, Clone, PartialEq)]
pub struct PointsAnchor {
    /// Index of the anchor frame (earlier than the measured one).
    pub frame: usize,
    /// The directions fixed by the points (orthonormal tangent vectors
    /// `(ρ, φ)`, sensor frame of the measured frame).
    pub directions: Vec<Vector6<f64>>,
}

/// One plane of one frame, associated with a landmark.
#[derive(Debug, Clone, PartialEq)]
pub struct LandmarkObservation {
    /// Index of the frame in the sequence.
    pub frame: usize,
    /// Id of the landmark ([`crate::map::Landmark::id`]).
    pub landmark: usize,
    /// Kind of the plane.
    pub kind: PlaneKind,
    /// The measured plane in the sensor frame (facing the sensor).
    pub plane: Plane,
    /// Number of inlier points.
    pub count: usize,
    /// Mean of the inliers (sensor frame).
    pub centroid: Point3<f64>,
    /// Centred scatter of the inliers (sensor frame).
    pub scatter: Matrix3<f64>,
}

impl LandmarkObservation {
    /// The observation of `plane` (sensor frame) of frame `frame` fused into
    /// landmark `landmark`.
    pub fn new(frame: usize, landmark: usize, plane: &FramePlane) -> Self {
        Self {
            frame,
            landmark,
            kind: plane.kind,
            plane: plane.plane,
            count: plane.inliers.len(),
            centroid: plane.centroid,
            scatter: plane.scatter,
        }
    }
}

/// The log of a tracking run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrackingLog {
    /// One entry per tracked frame, in order.
    pub frames: Vec<TrackedFrame>,
    /// Every plane observation, in frame order.
    pub observations: Vec<LandmarkObservation>,
    /// Verified loop closures, in the order they were found.
    pub loops: Vec<super::loop_closure::LoopConstraint>,
}
