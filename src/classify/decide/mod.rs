//! The decision procedure shared by the classifiers (the paper's "Global
//! Point Classification", applicable to one frame against any set of
//! bounded reflective planes). Each point also gets the [`Rule`] that
//! decided it.
//!
//! 1. Beam test: a point whose beam crosses no reflective plane inside its
//!    boundary is Normal. Otherwise, by its range `r` against the range `t`
//!    at which the beam crosses the first plane: `|r - t| <= glass_distance`
//!    is Glass (unless it is a single echo as bright as a wall, or a single
//!    echo far from normal incidence and brighter than the plane's glass
//!    echoes: a mullion or sill), `r < t` is Normal (in front), and
//!    `r > t + behind_distance` is behind the plane: a Reflection or an
//!    Obstacle.
//! 2. Behind-plane points are split by evidence, strongest first:
//!    - mirror: behind a landmark that transmits nothing, nothing is real;
//!    - two hypotheses against the space seen directly over the sequence
//!      (when the beam crossed one pane only): real where measured, or the
//!      mirror image of a real point; a hypothesis is refuted when its
//!      endpoint lies in seen-free space or its path runs through a seen
//!      surface, and when exactly one is refuted the other decides;
//!    - depth: a reflection appears as deep behind the plane as its real
//!      object stands in front, so a point deeper than every point seen in
//!      front is an Obstacle;
//!    - free space in the frame: mirrored through the plane, a reflection
//!      lands on a real surface; if the scan saw *through* that place (a
//!      return farther along the mirrored point's own beam) the point is an
//!      Obstacle;
//!    - echo strength: where the landmark's echoes behind it fall in two
//!      groups, the weak one reflected and the strong one transmitted (or
//!      the other way round, as its anchors say); a beam that met a second
//!      pane is decided pane by pane (weak at the first: reflected there;
//!      strong: through it, and the next pane decides);
//!    - seen surface: a point measured on a surface seen directly from
//!      elsewhere in the sequence is real (an Obstacle);
//!    - support: if the mirrored point lands on an observed surface (a return
//!      at that range in its beam, or a Normal point within a radius) it is a
//!      Reflection;
//!    - dual return: on a beam with two returns behind the plane whose far
//!      return is an Obstacle, the near return is a Reflection (the strongest
//!      echo came back off the glass; the last came through it).
//!
//!    Each is one function of `ladder.rs`, tried in this order until one
//!    decides; a beam past a plane's seen extent has its own, shorter
//!    ladder (`past_extent.rs`).
//! 3. What no evidence decides is `ambiguous` (the paper: unclassified, so
//!    it is removed from the filtered cloud).

use serde::{Deserialize, Serialize};

mod beam_hits;
mod beam_test;
mod frame_evidence;
mod hypotheses;
mod ladder;
mod mirror_support;
mod pane_edge;
mod past_extent;
mod past_pane;

pub use self::beam_hits::{BeamHit, BeamHits};
pub(crate) use self::beam_test::{beam_classes, beam_test, room_depths, Beam};
pub(crate) use self::frame_evidence::returns_along;
use self::frame_evidence::NormalPointIndex;
pub(crate) use self::hypotheses::leg_refuted;
use self::ladder::{dual_return, Ladder};
pub use self::mirror_support::SurfaceSupport;
pub(crate) use self::pane_edge::near_pane_edge;
use self::past_extent::past_seen_extent;
pub(crate) use self::past_extent::through_glass;
use super::boundary::BeamPlanes;
use super::rule::{Decisions, Rule};
use super::space::SensorFrameSpace;
use super::Class;
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// Thresholds and switches of the decision procedure.
///
/// Only the rule ladder's are configuration keys (`[plane_map.ladder]` of
/// `configs/paper.toml`, every key stated; `glass_distance` and
/// `behind_distance` come from `[plane_map.decision]`): the single-scan
/// baseline uses [`DecisionParams::ZHAO2020`], the weighed classifier
/// [`DecisionParams::WEIGHED`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionParams {
    /// Points within this range of the plane's crossing along their beam are
    /// on the surface, m.
    #[serde(skip, default = "glass_distance")]
    pub glass_distance: f64,
    /// Points farther than this behind the crossing (along the beam) are
    /// behind the plane, m (between `glass_distance` and this they are
    /// ambiguous).
    #[serde(skip, default = "glass_distance")]
    pub behind_distance: f64,
    /// Use the depth test.
    pub depth_test: bool,
    /// A point is deeper than the indoor points by more than this to be an
    /// Obstacle, m.
    pub depth_margin: f64,
    /// Use the free-space test on the organized scan.
    pub free_space_test: bool,
    /// A return this much farther than the mirrored point proves free space, m.
    pub free_space_margin: f64,
    /// ... plus this share of the mirrored point's range: an error in the
    /// plane's orientation moves mirrored points in proportion to their
    /// distance (0: a fixed margin, as Zhao 2020).
    pub free_space_margin_ratio: f64,
    /// Cells around the mirrored point's cell that must all show free space
    /// (0: the cell alone, as Zhao 2020; 1: the 3 × 3 block, robust to the
    /// ring and column quantisation of the mirrored direction).
    pub free_space_neighbourhood: usize,
    /// Which behind-plane points the free-space and depth tests apply to:
    /// only last returns (Zhao 2020) or every behind-plane point.
    pub obstacle_tests_on_all_returns: bool,
    /// Use support: the mirrored point lands on an observed surface.
    pub support_test: bool,
    /// Support within this range difference along the mirrored beam, m.
    pub support_range: f64,
    /// Support from a Normal point within this radius, m (0 disables the
    /// neighbour search; the paper's 0.1 m² squared radius is 0.316 m).
    pub support_radius: f64,
    /// Support counts only where the mirror image lies farther than
    /// `support_radius` from the point itself: nearer, the surface the
    /// point lies on supports its own mirror image (a wall a hand's breadth
    /// behind a glass door leaf parked against it), which is no evidence of
    /// a reflection.
    pub support_excludes_own_surface: bool,
    /// The sequence's seen surfaces support a mirror image only where it
    /// does not lie more than [`support_behind`](Self::support_behind)
    /// behind the nearest of them (along that surface's normal, turned
    /// towards the sensor that saw it): a reflected beam would have ended
    /// on that surface, so an image behind it is no reflection of it (a
    /// hedge outside a window mirrors to behind the room's side wall, within
    /// the support radius of the wall).
    pub support_behind_test: bool,
    /// How far behind a seen surface a mirror image may lie and still be
    /// supported by it, m: the mirror plane's and the poses' errors.
    pub support_behind: f64,
    /// Use the dual-return rule (the near return of an obstacle beam is a
    /// reflection).
    pub dual_return_rule: bool,
    /// Two returns further apart than this are distinct, m.
    pub dual_gap: f64,
    /// Class given to behind-plane points no evidence decides.
    pub ambiguous: Class,
    /// A single echo on a reflective plane that is stronger than the plane's
    /// glass echoes met at the same incidence (see the evidence grid,
    /// [`EvidenceGrid::is_opaque_echo`](crate::geometry::grid::EvidenceGrid::is_opaque_echo))
    /// is an opaque surface (Normal).
    pub wall_echo_test: bool,
    /// A single echo on a reflective plane met more than this many degrees
    /// from the plane's normal, and stronger than the plane's glass echoes
    /// met at the same incidence (where none was, brighter than their
    /// median), is an opaque surface (a mullion, a sill, a wall strip): glass
    /// returns a weak echo of its own away from normal incidence, and a
    /// beam through glass usually brings back a second return from behind
    /// (0: off).
    pub oblique_single_echo_deg: f64,
    /// Test both hypotheses of a behind-plane point against the space seen
    /// directly over the sequence ([`SpaceMap`](super::space::SpaceMap)):
    /// real where measured, or the mirror image of a real point. A
    /// hypothesis whose endpoint lies in seen-free space, or whose path
    /// beyond the plane runs through a seen surface, is refuted; when exactly
    /// one is refuted the other decides.
    pub space_test: bool,
    /// Paths are tested from this far off the plane and up to this far
    /// before their endpoint, m (frames and wall strips around a pane, the
    /// surface the endpoint itself lies on).
    pub space_margin: f64,
    /// A mirrored or measured position is in seen-free space only if no seen
    /// surface lies within this share of its range (at least a voxel): the
    /// plane's error moves mirrored positions in proportion.
    pub space_clearance_ratio: f64,
    /// A behind-plane point that lies on a surface seen directly over the
    /// sequence (an occupied voxel of the space map) is real: an Obstacle.
    /// Tested after the echo strength, before the mirror-image support.
    pub seen_surface_test: bool,
    /// A point found real by the seen-surface test or by its echo strength
    /// is an Obstacle only where the pane produced glass echoes within this
    /// distance of the beam's crossing (its evidence grid); with none there
    /// the beam passed an opening in the plane (a door, the air above a
    /// railing, a gap the pane's extent covers) and the point is Normal, m
    /// (0: always an Obstacle).
    pub seen_surface_echo_reach: f64,
    /// The first pane's echo split also decides beams that met a second
    /// pane behind it: a reflection off the first pane is weak whatever
    /// lies beyond, and a transmitted echo stays strong through uncoated
    /// glass (glass doors and partitions seen through one another), while
    /// the geometric tests say nothing past a second pane. Read by the
    /// ladder, which goes pane by pane (`past_pane.rs`); the weighed
    /// model's echo-strength test always weighs such beams, by the nearer
    /// pane's groups alone.
    pub echo_strength_past_second_pane: bool,
    /// A reflective landmark may continue as glass up to this far above
    /// its seen extent (up its plane), where its evidence calls the plane
    /// neither opaque nor open, m (0: off). Glass
    /// echoes only near normal incidence, and a sensor carried past a wall
    /// meets it so only near its own height: the top of a tall pane gives
    /// none and its extent ends short. A double-height facade (the atrium
    /// family's, glass to 6.5 m) echoes up to about 3 m, and its glass goes
    /// on for 3 to 4 m more (`docs/decision.md`, "Glass past its last
    /// echo"). A point whose beam crossed that continuation is tested like
    /// a point behind glass, but only by the evidence of the whole
    /// sequence: a Reflection where its real position is refuted, or where
    /// its mirror image lands on a seen surface and no surface was seen
    /// where it was measured; Normal otherwise. The space seen directly
    /// takes no surface from such beams.
    pub unseen_extent: f64,
    /// How far the same continuation reaches beside and below the seen
    /// extent, m: the sensor met the plane head-on where it passed, so
    /// beside a pane glass hides only at the ends of what it passed (and a
    /// small reflective plane, a screen on a desk, does not continue over
    /// the desk); below, glass meets a floor or a parapet, and a beam
    /// below a pane's foot is one the space seen directly needs (the
    /// lobby's ghost landmark, `tests/plane_optimized.rs`).
    pub unseen_extent_beside: f64,
    /// A beam that crossed a landmark's extent within this distance of its
    /// edge may have passed beside it, m (0: off): the panes are fitted on
    /// the evidence grid's 0.2 m cells and overreach by up to about half a
    /// cell. Such a beam is no evidence that the landmark transmits (its
    /// mirror test counts only beams well inside), and behind a mirror the
    /// point it reached is Normal where the space seen directly says it is
    /// real (its mirror image refuted, or a surface seen there): seen past
    /// the mirror's edge, not through it.
    pub pane_edge_margin: f64,
    /// Support from a seen surface within this many degrees of
    /// perpendicular to the mirror plane is no evidence, deg (0: off). A
    /// floor or ceiling that continues across the glass is its own mirror
    /// image: a point on its far side (an obstacle) and a reflection of its
    /// near side land at the same place, so the support test calls both
    /// Reflections. With this on such points are left to the later rules
    /// and otherwise unclassified, never guessed; it also leaves real floor
    /// reflections unclassified, so it is off by default (datasets/README.md
    /// has the trade-off).
    pub perpendicular_support_deg: f64,
}

/// The 0.1 m of `glass_distance` and `behind_distance` until
/// `[plane_map.decision]` sets them (serde's default for a ladder table).
fn glass_distance() -> f64 {
    0.1
}

impl DecisionParams {
    /// Zhao 2020's single-scan decision (the baseline the paper compares
    /// against): the depth and free-space tests on last returns, a fixed
    /// 0.1 m free-space margin, the mirrored point's cell alone, and the
    /// dual-return rule; none of the sequence's evidence.
    pub const ZHAO2020: Self = Self {
        glass_distance: 0.1,
        behind_distance: 0.1,
        depth_test: true,
        depth_margin: 0.0,
        free_space_test: true,
        free_space_margin: 0.1,
        free_space_margin_ratio: 0.0,
        free_space_neighbourhood: 0,
        obstacle_tests_on_all_returns: false,
        support_test: false,
        support_range: 0.1,
        support_radius: 0.0,
        support_excludes_own_surface: false,
        support_behind_test: false,
        support_behind: 0.2,
        dual_return_rule: true,
        dual_gap: 0.1,
        ambiguous: Class::Unclassified,
        wall_echo_test: false,
        oblique_single_echo_deg: 0.0,
        space_test: false,
        space_margin: 0.2,
        space_clearance_ratio: 0.0,
        seen_surface_test: false,
        seen_surface_echo_reach: 0.0,
        echo_strength_past_second_pane: false,
        unseen_extent: 0.0,
        unseen_extent_beside: 0.0,
        pane_edge_margin: 0.0,
        perpendicular_support_deg: 0.0,
    };

    /// What the weighed classifier (`plane_map.decision_model = "weighed"`)
    /// takes from the decision procedure: its beam test (a single echo
    /// stronger than the plane's glass echoes at its incidence is wall; one
    /// beyond 30 deg from the normal, stronger than them, a mullion or sill;
    /// glass may continue 4 m above its last echo, 1 m beside and below
    /// it; a point found real is an Obstacle only with glass echoes within
    /// 0.6 m of its beam's crossing),
    /// the space seen directly from every pose (always tested), the
    /// sequence's surface support within 0.316 m (the paper's 0.1 m²
    /// squared radius) but not more than 0.2 m behind a seen surface, and a
    /// 0.15 m margin at a pane's edge (panes overreach by about half a
    /// 0.2 m evidence cell). `glass_distance` and `behind_distance` come
    /// from `[plane_map.decision]`.
    pub const WEIGHED: Self = Self {
        glass_distance: 0.1,
        behind_distance: 0.1,
        depth_test: true,
        depth_margin: 0.1,
        free_space_test: true,
        free_space_margin: 0.1,
        free_space_margin_ratio: 0.01,
        free_space_neighbourhood: 1,
        obstacle_tests_on_all_returns: true,
        support_test: true,
        support_range: 0.1,
        support_radius: 0.316,
        support_excludes_own_surface: true,
        support_behind_test: true,
        support_behind: 0.2,
        dual_return_rule: true,
        dual_gap: 0.1,
        ambiguous: Class::Unclassified,
        wall_echo_test: true,
        oblique_single_echo_deg: 30.0,
        space_test: true,
        space_margin: 0.2,
        space_clearance_ratio: 0.02,
        seen_surface_test: true,
        seen_surface_echo_reach: 0.6,
        echo_strength_past_second_pane: true,
        unseen_extent: 4.0,
        unseen_extent_beside: 1.0,
        pane_edge_margin: 0.15,
        perpendicular_support_deg: 0.0,
    };
}

impl Default for DecisionParams {
    /// [`DecisionParams::ZHAO2020`].
    fn default() -> Self {
        Self::ZHAO2020
    }
}

/// Classify every point of `frame` against `planes`.
///
/// `support` adds the neighbour search of the support test; `None` uses only
/// the frame's own Normal points when `support_radius > 0`.
pub fn decide(
    frame: &Frame,
    scan: &OrganizedScan,
    sensor: &SensorModel,
    planes: &BeamPlanes<'_>,
    params: &DecisionParams,
    support: Option<&dyn SurfaceSupport>,
) -> Decisions {
    let hits = BeamHits::compute(frame, scan, planes, params.glass_distance);
    decide_with_hits(
        frame,
        scan,
        sensor,
        planes.planes(),
        &hits,
        params,
        support,
        None,
    )
}

/// [`decide`] with the beam test already done: `hits` from
/// [`BeamHits::compute`] with reach `params.glass_distance` against
/// `bounded`; `space` is the sequence's directly seen space from this
/// frame's pose, for the two-hypothesis test. The steps of the module
/// documentation, in order; a point keeps the first decision it gets.
#[allow(clippy::too_many_arguments)]
pub fn decide_with_hits(
    frame: &Frame,
    scan: &OrganizedScan,
    sensor: &SensorModel,
    bounded: &[BoundedPlane],
    hits: &BeamHits,
    params: &DecisionParams,
    support: Option<&dyn SurfaceSupport>,
    space: Option<&SensorFrameSpace<'_>>,
) -> Decisions {
    let beams = beam_test(frame, scan, bounded, hits, params);
    let (mut classes, mut rules) = beam_classes(&beams);
    if bounded.is_empty() {
        return hard_decisions(classes, rules);
    }

    let own_support = (params.support_test && params.support_radius > 0.0 && support.is_none())
        .then(|| NormalPointIndex::new(frame, &classes));
    let support: Option<&dyn SurfaceSupport> = match (&own_support, support) {
        (Some(own), _) => Some(own),
        (None, s) => s,
    };
    let ladder = Ladder {
        frame,
        scan,
        sensor,
        bounded,
        one_sided: BeamPlanes::hulls(bounded, 0.0),
        max_indoor: room_depths(frame, bounded, &classes),
        params,
        support,
        space,
    };

    // 2. Evidence for behind-plane points, the first rule that decides.
    for (i, beam) in beams.iter().enumerate() {
        let decision = match *beam {
            Beam::Unseen { plane } => past_seen_extent(
                frame,
                scan,
                sensor,
                &bounded[plane as usize],
                i,
                params,
                support,
                space,
            ),
            Beam::Behind { plane } => ladder.behind_plane(i, plane as usize),
            _ => None,
        };
        if let Some(decision) = decision {
            (classes[i], rules[i]) = decision;
        }
    }
    if params.dual_return_rule {
        dual_return(
            frame,
            scan,
            &beams,
            &mut classes,
            &mut rules,
            params.dual_gap,
        );
    }

    // 3. Undecided behind-plane points.
    for (c, b) in classes.iter_mut().zip(&beams) {
        if matches!(b, Beam::Behind { .. }) && *c == Class::Unclassified {
            *c = params.ambiguous;
        }
    }
    hard_decisions(classes, rules)
}

/// The ladder's decisions with their confidence: a rule decides outright, so
/// a decided point has confidence 1 and an undecided one 0.5 (either class).
pub(crate) fn hard_decisions(classes: Vec<Class>, rules: Vec<Rule>) -> Decisions {
    let confidence = classes
        .iter()
        .map(|c| if *c == Class::Unclassified { 0.5 } else { 1.0 })
        .collect();
    Decisions {
        classes,
        rules,
        confidence,
    }
}

#[cfg(test)]
pub(crate) mod tests;
