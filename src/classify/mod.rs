//! Per-point classification: Normal, reflective surface (Glass),
//! Reflection, Obstacle behind glass, and the mirror-back of reflections.
//!
//! A [`Classifier`] decides every point of a frame given the reflective
//! planes that bound its beams. Two implementations share one decision
//! procedure ([`decide`]):
//! - [`SingleScanClassifier`]: the Zhao 2020 method the paper compares
//!   against, planes from the frame's own detection;
//! - the plane-map classifier of the plane-optimized pipeline (planes from
//!   the global map).

pub mod boundary;
pub mod decide;
pub mod evidence;
pub mod landmark_echoes;
pub mod levels;
pub mod mirror;
pub mod plane_map;
pub mod rule;
pub mod single_scan;
pub mod space;
pub mod support;
pub mod weighed;

pub use decide::{BeamHit, BeamHits, DecisionParams, SurfaceSupport};
pub use landmark_echoes::EchoCounting;
pub use plane_map::{DecisionModel, PlaneMapClassifier, PlaneMapParams};
pub use rule::{Decisions, Rule, RuleTally};
pub use single_scan::SingleScanClassifier;
pub use space::{Occupancy, SpaceMap};
pub use support::{SupportBuilder, WorldSupport};

use serde::{Deserialize, Serialize};

use nalgebra::Isometry3;

use crate::cloud::Frame;
use crate::reflect::{BoundedPlane, Detection};
use crate::sensor::{OrganizedScan, SensorModel};

/// Predicted class of a point, with the prediction ids of the design brief.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
#[repr(u8)]
pub enum Class {
    /// Not classified (removed from the filtered cloud).
    #[default]
    Unclassified = 0,
    /// An ordinary surface in front of (or away from) every reflective plane.
    Normal = 1,
    /// On a reflective surface (glass or mirror).
    Glass = 2,
    /// A virtual point: a reflection seen behind a reflective surface.
    Reflection = 5,
    /// A real object seen through glass.
    Obstacle = 6,
}

impl Class {
    /// The prediction id written to `.label` files.
    pub fn id(self) -> u8 {
        self as u8
    }

    /// The class of a prediction id (unknown ids are unclassified).
    pub fn from_id(id: u32) -> Self {
        match id {
            1 => Class::Normal,
            2 => Class::Glass,
            5 => Class::Reflection,
            6 => Class::Obstacle,
            _ => Class::Unclassified,
        }
    }

    /// Short name used in tables.
    pub fn name(self) -> &'static str {
        match self {
            Class::Unclassified => "unclassified",
            Class::Normal => "normal",
            Class::Glass => "glass",
            Class::Reflection => "reflection",
            Class::Obstacle => "obstacle",
        }
    }
}

/// Everything a classifier may use about one frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameInput<'a> {
    /// The frame (sensor frame points).
    pub frame: &'a Frame,
    /// Its organized scan.
    pub scan: &'a OrganizedScan,
    /// The sensor model (ring lookup for mirrored points).
    pub sensor: &'a SensorModel,
    /// The frame's own detection (candidates, planes, inliers).
    pub detection: &'a Detection,
    /// `T_world_sensor` of the frame (identity when unknown).
    pub pose: Isometry3<f64>,
    /// Reflective planes of the global map (world frame); empty when there
    /// is no map.
    pub map_planes: &'a [BoundedPlane],
    /// Observed surfaces of the whole sequence (world frame), when built.
    pub support: Option<&'a WorldSupport>,
    /// Space seen directly over the whole sequence (world frame), when
    /// built.
    pub space: Option<&'a SpaceMap>,
    /// The beam test against `map_planes`, when a pipeline has run it
    /// already ([`PlaneMapClassifier::beam_hits`]); `None` runs it here.
    pub beam_hits: Option<&'a BeamHits>,
}

/// Classifies every point of a frame. Implementations are selected by name
/// in the configuration.
pub trait Classifier: Send + Sync {
    /// The name this classifier is selected by.
    fn name(&self) -> &'static str;

    /// One class per point, in the frame's point order, with the rule that
    /// decided each.
    fn classify(&self, input: &FrameInput<'_>) -> Decisions;
}
