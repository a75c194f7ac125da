//! The paper's global classification: every frame against the reflective
//! planes of the global map, with the map's fused hull boundaries and,
//! beyond the paper, the observed surfaces of all frames as mirror support.

use serde::{Deserialize, Serialize};

use super::boundary::BeamPlanes;
use super::decide::{decide_with_hits, BeamHits, DecisionParams, SurfaceSupport};
use super::evidence::{Weighing, WeighingParams};
use super::weighed::{decide_weighed, FrameContext};
use super::{Classifier, Decisions, FrameInput};
use crate::map::MirrorParams;
use crate::reflect::{planes_seen_from, BoundedPlane, EchoSplitParams};

/// How points behind a reflective plane are decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum DecisionModel {
    /// Every evidence test weighed against the landmark's glass-or-mirror
    /// prior ([`Weighing`]).
    #[default]
    Weighed,
    /// The paper's first-match rules ([`decide_with_hits`]).
    Ladder,
}

/// Parameters of the plane-map classifier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlaneMapParams {
    /// How points behind a reflective plane are decided.
    pub decision_model: DecisionModel,
    /// Hull growth, metres.
    pub hull_margin: f64,
    /// Use the observed surfaces of all frames for the support test (the
    /// paper uses the current frame only).
    pub sequence_support: bool,
    /// Voxel size used to thin the sequence's surface points, m.
    pub support_voxel: f64,
    /// A frame adds its surfaces to the support when the sensor moved this
    /// far since the last frame that did, m (0 adds every frame).
    pub support_keyframe_move: f64,
    /// ... or turned this much, degrees.
    pub support_keyframe_turn_deg: f64,
    /// Voxel edge of the directly seen space (two-hypothesis test), m.
    pub space_voxel: f64,
    /// Beams that must pass a voxel before it counts as free.
    pub space_min_passes: u8,
    /// Returns from a voxel needed before it blocks a path.
    pub space_block_hits: u8,
    /// One beam column in this many carves free space (all mark surfaces):
    /// neighbouring beams pass nearly the same voxels.
    pub space_column_stride: usize,
    /// Carving stops this share of the range before a beam's endpoint (and
    /// at least two voxels): beam footprint and grazing incidence.
    pub space_stop_ratio: f64,
    /// A frame carves the space when the sensor moved this far since the
    /// last frame that did, m ...
    pub space_keyframe_move: f64,
    /// ... or turned this much, degrees.
    pub space_keyframe_turn_deg: f64,
    /// Per-landmark split of reflected and transmitted echoes by strength.
    pub echo_split: EchoSplitParams,
    /// The decision thresholds and switches (the ladder's; the beam test's
    /// for both models).
    pub decision: DecisionParams,
    /// Glass or mirror per landmark.
    pub mirror: MirrorParams,
    /// The evidence weighed behind reflective planes.
    pub weighing: WeighingParams,
}

impl Default for PlaneMapParams {
    fn default() -> Self {
        Self {
            decision_model: DecisionModel::Weighed,
            mirror: MirrorParams::default(),
            weighing: WeighingParams::default(),
            hull_margin: 0.0,
            sequence_support: false,
            support_voxel: 0.05,
            support_keyframe_move: 0.0,
            support_keyframe_turn_deg: 0.0,
            space_voxel: 0.1,
            space_min_passes: 2,
            space_block_hits: 5,
            space_column_stride: 1,
            space_stop_ratio: 0.05,
            space_keyframe_move: 0.25,
            space_keyframe_turn_deg: 10.0,
            echo_split: EchoSplitParams::default(),
            decision: DecisionParams {
                depth_margin: 0.1,
                obstacle_tests_on_all_returns: true,
                support_test: true,
                support_radius: 0.316,
                ..DecisionParams::default()
            },
        }
    }
}

/// Classifies a frame against the global map's reflective planes.
#[derive(Debug)]
pub struct PlaneMapClassifier {
    params: PlaneMapParams,
    weighing: Weighing,
}

impl PlaneMapClassifier {
    /// A classifier with the given parameters; an evidence test the
    /// weighing does not know is an error.
    pub fn new(params: PlaneMapParams) -> crate::Result<Self> {
        let weighing = Weighing::from_params(&params.weighing)?;
        Ok(Self { params, weighing })
    }

    /// This classifier weighing `weighing` instead of the tests its
    /// parameters list (a researcher's own tests).
    pub fn with_weighing(mut self, weighing: Weighing) -> Self {
        self.weighing = weighing;
        self
    }

    /// The parameters.
    pub fn params(&self) -> &PlaneMapParams {
        &self.params
    }

    /// The map planes in the frame's sensor frame, facing the sensor.
    pub fn planes_in_sensor_frame(input: &FrameInput<'_>) -> Vec<BoundedPlane> {
        planes_seen_from(input.map_planes, &input.pose)
    }

    /// The beam test of every point against the map planes (sensor frame),
    /// as [`Classifier::classify`] runs it; pass it in
    /// [`FrameInput::beam_hits`] to run it only once per frame.
    pub fn beam_hits(&self, input: &FrameInput<'_>) -> BeamHits {
        let planes = Self::planes_in_sensor_frame(input);
        let beams = BeamPlanes::hulls(&planes, self.params.hull_margin)
            .with_unseen_extent(self.params.decision.unseen_extent);
        BeamHits::compute(
            input.frame,
            input.scan,
            &beams,
            self.params.decision.glass_distance,
        )
    }

    /// Indices of the points whose beams cross no map plane or stop in front
    /// of it, by the beam test `hits` ([`PlaneMapClassifier::beam_hits`]):
    /// the frame's observed ordinary surfaces (Normal by the beam test
    /// alone), used to build the sequence's surface support.
    pub fn surface_points(&self, input: &FrameInput<'_>, hits: &BeamHits) -> Vec<u32> {
        let planes = Self::planes_in_sensor_frame(input);
        let glass = self.params.decision.glass_distance;
        input
            .frame
            .points
            .iter()
            .enumerate()
            .filter(|(i, pt)| {
                let p = pt.position();
                // A return behind a plane's unseen continuation may be a
                // mirror image: not a surface seen directly.
                match hits.get(*i, &p, &planes).or(hits.unseen(*i, &p, &planes)) {
                    None => true,
                    Some(h) => p.coords.norm() < h.range - glass,
                }
            })
            .map(|(i, _)| i as u32)
            .collect()
    }
}

impl Classifier for PlaneMapClassifier {
    fn name(&self) -> &'static str {
        "plane-map"
    }

    fn classify(&self, input: &FrameInput<'_>) -> Decisions {
        let planes = Self::planes_in_sensor_frame(input);
        let view = input
            .support
            .filter(|_| self.params.sequence_support)
            .map(|s| s.in_sensor_frame(input.pose));
        let support = view.as_ref().map(|v| v as &dyn SurfaceSupport);
        let weighed = self.params.decision_model == DecisionModel::Weighed;
        let space = input
            .space
            .filter(|_| weighed || self.params.decision.space_test)
            .map(|s| s.in_sensor_frame(input.pose));
        let own_hits;
        let hits = match input.beam_hits {
            Some(h) => h,
            None => {
                own_hits = self.beam_hits(input);
                &own_hits
            }
        };
        if weighed {
            let ctx = FrameContext {
                frame: input.frame,
                scan: input.scan,
                sensor: input.sensor,
                bounded: &planes,
                hits,
                support,
                space: space.as_ref(),
            };
            return decide_weighed(&ctx, &self.params.decision, &self.weighing);
        }
        decide_with_hits(
            input.frame,
            input.scan,
            input.sensor,
            &planes,
            hits,
            &self.params.decision,
            support,
            space.as_ref(),
        )
    }
}
