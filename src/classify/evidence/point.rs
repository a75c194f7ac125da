//! What every test may look at for one point behind a reflective landmark.

use nalgebra::Point3;

use crate::classify::decide::SurfaceSupport;
use crate::classify::space::SensorFrameSpace;
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// One point behind a reflective landmark, in the frame's sensor frame,
/// with everything known about it and around it.
#[derive(Clone, Copy)]
pub struct BehindPoint<'a> {
    /// Index of the point in its frame.
    pub index: usize,
    /// Where it was measured (sensor frame).
    pub position: Point3<f64>,
    /// Its range, m.
    pub range: f64,
    /// The landmark its beam crossed first (sensor frame, facing the
    /// sensor).
    pub landmark: &'a BoundedPlane,
    /// Range at which the beam crossed the landmark, m.
    pub crossing: f64,
    /// Its mirror image across the landmark: where it would be if it were
    /// a reflection.
    pub mirrored: Point3<f64>,
    /// Whether its beam crossed no other pane before it (past a second pane
    /// the first one's mirror image says nothing).
    pub single_pane: bool,
    /// Whether the beam crossed the landmark beyond its seen extent, where
    /// glass may continue without an echo: if real, it was seen through an
    /// opening (Normal), not glass.
    pub past_extent: bool,
    /// The deepest point of the frame in front of the landmark, measured
    /// behind it along its normal, m: the room the reflection could come
    /// from.
    pub room_depth: f64,
    /// The frame.
    pub frame: &'a Frame,
    /// Its organized scan.
    pub scan: &'a OrganizedScan,
    /// The sensor model.
    pub sensor: &'a SensorModel,
    /// The space seen directly over the sequence, from this frame's pose.
    pub space: Option<&'a SensorFrameSpace<'a>>,
    /// Whether it was measured in a voxel where a surface was seen through
    /// its landmark (the space seen through glass: confirmed transmissions'
    /// ends, and voxels where most echoes behind the landmark were on the
    /// transmitted side of its split): 3DRef labels it an Obstacle whatever
    /// path its echo took. False past a second pane or without that map.
    pub on_surface_seen_through: bool,
    /// Surfaces observed over the sequence (or in the frame).
    pub support: Option<&'a dyn SurfaceSupport>,
}

impl BehindPoint<'_> {
    /// Its depth behind the landmark along the landmark's normal, m.
    pub fn depth(&self) -> f64 {
        -self.landmark.plane.signed_distance(&self.position)
    }

    /// Where its beam crossed the landmark (sensor frame).
    pub fn crossing_point(&self) -> Point3<f64> {
        Point3::from(self.position.coords * (self.crossing / self.range))
    }

    /// The echo's intensity.
    pub fn intensity(&self) -> f32 {
        self.frame.points[self.index].intensity
    }
}
