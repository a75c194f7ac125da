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
///
/// Read from `[plane_map]` (four keys and its tables); the space map's
/// and the hulls' parameters are method constants ([`SPACE`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PlaneMapKeys", into = "PlaneMapKeys")]
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
    /// Per-landmark split of reflected and transmitted echoes by strength
    /// (`None`: no split).
    pub echo_split: Option<EchoSplitParams>,
    /// The decision thresholds and switches in use: the ladder's
    /// (`[plane_map.ladder]`) with the ladder, [`DecisionParams::WEIGHED`]
    /// with the weighed model; `glass_distance` and `behind_distance` from
    /// `[plane_map.decision]` for both.
    pub decision: DecisionParams,
    /// The rule ladder's thresholds and switches as configured
    /// (`[plane_map.ladder]`, required by `decision_model = "ladder"`).
    pub ladder: Option<DecisionParams>,
    /// Glass or mirror per landmark.
    pub mirror: MirrorParams,
    /// The evidence weighed behind reflective planes.
    pub weighing: WeighingParams,
}

/// The space seen directly, method constants: 0.1 m voxels are set by
/// `plane_map.space_voxel`; a voxel is free after 2 beams passed it and
/// blocks a path after 5 returns (stray returns do not); one column in 3
/// carves (1.8 degrees apart, about the ring spacing); carving stops 5 % of
/// the range (and two voxels) short of the endpoint; a keyframe carves
/// whenever the sensor moved 0.25 m or turned 10 degrees. The hulls are not
/// grown.
pub struct SpaceConstants {
    /// Beams that must pass a voxel before it counts as free.
    pub min_passes: u8,
    /// Returns from a voxel needed before it blocks a path.
    pub block_hits: u8,
    /// One beam column in this many carves.
    pub column_stride: usize,
    /// Carving stops this share of the range before the endpoint.
    pub stop_ratio: f64,
    /// Keyframe spacing, m.
    pub keyframe_move: f64,
    /// Keyframe spacing, degrees.
    pub keyframe_turn_deg: f64,
}

/// The space map's constants ([`SpaceConstants`]).
pub const SPACE: SpaceConstants = SpaceConstants {
    min_passes: 2,
    block_hits: 5,
    column_stride: 3,
    stop_ratio: 0.05,
    keyframe_move: 0.25,
    keyframe_turn_deg: 10.0,
};

/// The keys of `[plane_map]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneMapKeys {
    /// How points behind a reflective plane are decided: `weighed` or the
    /// paper's `ladder`.
    decision_model: DecisionModel,
    /// Use the observed surfaces of all frames (every frame that moved) as
    /// mirror support (the paper: the current frame only).
    sequence_support: bool,
    /// Voxel edge that thins the sequence's surface points, m.
    support_voxel: f64,
    /// Voxel edge of the space seen directly, m.
    space_voxel: f64,
    /// The echo split (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    echo_split: Option<EchoSplitParams>,
    /// The beam test's distances, both models.
    decision: BeamKeys,
    /// The rule ladder (absent: only the weighed model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ladder: Option<DecisionParams>,
    #[serde(default)]
    mirror: MirrorParams,
    #[serde(default)]
    weighing: WeighingParams,
}

/// The keys of `[plane_map.decision]`: the beam test's distances.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BeamKeys {
    /// A point within this range of a plane's crossing along its beam is on
    /// the surface (glass), m.
    glass_distance: f64,
    /// A point farther than this behind the crossing is behind the plane,
    /// m (between `glass_distance` and this: ambiguous).
    behind_distance: f64,
}

impl TryFrom<PlaneMapKeys> for PlaneMapParams {
    type Error = String;

    fn try_from(k: PlaneMapKeys) -> Result<Self, String> {
        let beam = |d: DecisionParams| DecisionParams {
            glass_distance: k.decision.glass_distance,
            behind_distance: k.decision.behind_distance,
            ..d
        };
        let decision = match (k.decision_model, k.ladder) {
            (DecisionModel::Weighed, _) => beam(DecisionParams::WEIGHED),
            (DecisionModel::Ladder, Some(ladder)) => beam(ladder),
            (DecisionModel::Ladder, None) => {
                return Err("plane_map.decision_model = \"ladder\" needs the ladder's \
                     thresholds, [plane_map.ladder] (configs/paper.toml states the \
                     paper's: extends = \"paper\")"
                    .into())
            }
        };
        Ok(Self {
            decision_model: k.decision_model,
            hull_margin: 0.0,
            sequence_support: k.sequence_support,
            support_voxel: k.support_voxel,
            space_voxel: k.space_voxel,
            space_min_passes: SPACE.min_passes,
            space_block_hits: SPACE.block_hits,
            space_column_stride: SPACE.column_stride,
            space_stop_ratio: SPACE.stop_ratio,
            space_keyframe_move: SPACE.keyframe_move,
            space_keyframe_turn_deg: SPACE.keyframe_turn_deg,
            echo_split: k.echo_split,
            decision,
            ladder: k.ladder.map(beam),
            mirror: k.mirror,
            weighing: k.weighing,
        })
    }
}

impl From<PlaneMapParams> for PlaneMapKeys {
    fn from(p: PlaneMapParams) -> Self {
        Self {
            decision_model: p.decision_model,
            sequence_support: p.sequence_support,
            support_voxel: p.support_voxel,
            space_voxel: p.space_voxel,
            echo_split: p.echo_split,
            decision: BeamKeys {
                glass_distance: p.decision.glass_distance,
                behind_distance: p.decision.behind_distance,
            },
            ladder: p.ladder,
            mirror: p.mirror,
            weighing: p.weighing,
        }
    }
}

impl Default for PlaneMapParams {
    /// `[plane_map]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("plane_map")
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
        let beams = BeamPlanes::hulls(&planes, self.params.hull_margin).with_unseen_extent(
            self.params.decision.unseen_extent,
            self.params.decision.unseen_extent_beside,
        );
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
