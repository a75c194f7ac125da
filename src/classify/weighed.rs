//! The weighed decision behind the glass: the beam test places every point
//! on, in front of or behind the first reflective plane its beam crosses;
//! each point behind one gets the posterior of the evidence
//! ([`Weighing`]), and the class with the higher posterior where it reaches
//! the threshold.

use super::boundary::{beam_crossing, BeamPlanes};
use super::decide::{
    beam_classes, beam_test, room_depths, through_glass, Beam, BeamHits, DecisionParams,
    SurfaceSupport,
};
use super::evidence::{BehindPoint, Weighing};
use super::rule::{Decisions, Rule};
use super::space::SensorFrameSpace;
use super::Class;
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// A point whose beam crossed a plane beyond its seen extent is behind glass
/// with this probability: glass echoes only near normal incidence, so a
/// pane's top may continue unseen, or the plane may be open there.
const UNSEEN_GLASS: f64 = 0.5;

/// What the weighing needs of one frame besides the point itself.
pub struct FrameContext<'a> {
    /// The frame (sensor frame points).
    pub frame: &'a Frame,
    /// Its organized scan.
    pub scan: &'a OrganizedScan,
    /// The sensor model.
    pub sensor: &'a SensorModel,
    /// The reflective planes (sensor frame, facing the sensor).
    pub bounded: &'a [BoundedPlane],
    /// The beam test against `bounded`.
    pub hits: &'a BeamHits,
    /// Surfaces observed over the sequence.
    pub support: Option<&'a dyn SurfaceSupport>,
    /// The space seen directly over the sequence, from the frame's pose.
    pub space: Option<&'a SensorFrameSpace<'a>>,
}

/// Classify every point of a frame: the beam test, then the weighed
/// evidence behind the planes. `params` gives the beam test's thresholds.
pub fn decide_weighed(
    ctx: &FrameContext<'_>,
    params: &DecisionParams,
    weighing: &Weighing,
) -> Decisions {
    let beams = beam_test(ctx.frame, ctx.scan, ctx.bounded, ctx.hits, params);
    let (mut classes, mut rules) = beam_classes(&beams);
    // The beam test decides by geometry given the map.
    let mut confidence: Vec<f32> = classes
        .iter()
        .map(|c| if *c == Class::Unclassified { 0.5 } else { 1.0 })
        .collect();
    if ctx.bounded.is_empty() {
        return Decisions {
            classes,
            rules,
            confidence,
        };
    }
    let room = room_depths(ctx.frame, ctx.bounded, &classes);
    let one_sided = BeamPlanes::hulls(ctx.bounded, 0.0);
    for (i, beam) in beams.iter().enumerate() {
        let (plane, past_extent) = match *beam {
            Beam::Behind { plane } => (plane as usize, false),
            Beam::Unseen { plane } => (plane as usize, true),
            _ => continue,
        };
        let landmark = &ctx.bounded[plane];
        let position = ctx.frame.points[i].position();
        let range = position.coords.norm();
        let crossing = beam_crossing(&landmark.plane, &position).unwrap_or(range);
        let single_pane = !one_sided.second_pane(
            &position,
            plane,
            crossing,
            params.glass_distance,
            params.behind_distance,
        );
        let point = BehindPoint {
            index: i,
            position,
            range,
            landmark,
            crossing,
            mirrored: landmark.plane.mirror(&position),
            single_pane,
            // Nothing is seen through a mirror: behind one, strong echoes
            // are bright reflections, no surface.
            on_surface_seen_through: single_pane
                && !landmark.is_mirror()
                && ctx
                    .space
                    .and_then(|s| s.through_surface_at(&position))
                    .unwrap_or(false),
            past_extent,
            room_depth: room[plane],
            frame: ctx.frame,
            scan: ctx.scan,
            sensor: ctx.sensor,
            space: ctx.space,
            support: ctx.support,
        };
        (classes[i], confidence[i], rules[i]) = decide_point(&point, params, weighing);
    }
    Decisions {
        classes,
        rules,
        confidence,
    }
}

/// The class of one point behind a plane, its confidence and the rule to
/// report: the class whose posterior passes the weighing's threshold
/// (real is an Obstacle where the beam passed glass, Normal where it passed
/// an opening, beside a mirror or beyond the plane's seen extent), else
/// unclassified.
fn decide_point(
    point: &BehindPoint<'_>,
    params: &DecisionParams,
    weighing: &Weighing,
) -> (Class, f32, Rule) {
    let mut posterior = weighing.weigh(point);
    if point.past_extent {
        posterior.reflection = unseen_posterior(posterior.reflection, posterior.prior);
    }
    let p = posterior.reflection;
    let threshold = weighing.threshold();
    let (class, conf) = if p > threshold {
        (Class::Reflection, p)
    } else if 1.0 - p > threshold {
        let through = through_glass(
            point.landmark,
            &point.position,
            point.crossing,
            params.seen_surface_echo_reach,
        );
        // Nothing is seen through a mirror: a real point behind one was
        // reached beside it.
        let real = if !point.past_extent && through && !point.landmark.is_mirror() {
            Class::Obstacle
        } else {
            Class::Normal
        };
        (real, 1.0 - p)
    } else {
        (Class::Unclassified, p.max(1.0 - p))
    };
    let rule = if point.past_extent && class == Class::Reflection {
        Rule::PastSeenExtent
    } else {
        posterior.rule
    };
    (class, conf as f32, rule)
}

/// The posterior of a point past a plane's seen extent: the weighing's
/// posterior `glass_posterior` (which assumed glass, from `prior`) mixed
/// with "no glass there" (then it is real), by the prior odds of glass
/// continuing unseen.
fn unseen_posterior(glass_posterior: f64, prior: f64) -> f64 {
    // Bayes over the two explanations of the beam: glass there (the
    // weighing's likelihood ratio against its prior) or no glass (real).
    let odds = |p: f64| p / (1.0 - p).max(1e-12);
    let likelihood = odds(glass_posterior) / odds(prior);
    let r = UNSEEN_GLASS * prior * likelihood;
    let real = UNSEEN_GLASS * (1.0 - prior) + (1.0 - UNSEEN_GLASS);
    r / (r + real)
}
