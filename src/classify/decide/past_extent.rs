//! Points whose beam crossed a landmark where the pane's extent is in
//! doubt: past its last glass echo, where glass may continue unseen
//! ([`DecisionParams::unseen_extent`]), or inside an extent that
//! overreaches its echoes (an opening the pane covers).

use nalgebra::Point3;

use super::frame_evidence::returns_along;
use super::hypotheses::{two_hypotheses, Verdict};
use super::mirror_support::supports_itself;
use super::{DecisionParams, SurfaceSupport};
use crate::classify::rule::Rule;
use crate::classify::space::{Occupancy, SensorFrameSpace};
use crate::classify::Class;
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// Whether the beam towards `p`, crossing `bp` at range `t`, passed glass:
/// the landmark gave glass echoes within `reach` of the crossing (its
/// evidence grid). Without any there, a real point behind the plane was
/// seen through an opening the pane's extent covers (a door, the air above
/// a railing), and is Normal, not an Obstacle (`reach` 0: always glass).
pub(crate) fn through_glass(bp: &BoundedPlane, p: &Point3<f64>, t: f64, reach: f64) -> bool {
    reach <= 0.0
        || bp.evidence.as_ref().is_none_or(|e| {
            let crossing = Point3::from(p.coords * (t / p.coords.norm()));
            e.echoes_near(&bp.chart.to_2d(&crossing), reach) > 0
        })
}

/// The decision for point `i` behind the unseen continuation of `bp`'s
/// extent ([`DecisionParams::unseen_extent`]), from the sequence's evidence
/// only (the frame's depth, free-space and echo tests assume a pane):
/// `None` keeps it Normal.
#[allow(clippy::too_many_arguments)]
pub(super) fn past_seen_extent(
    frame: &Frame,
    scan: &OrganizedScan,
    sensor: &SensorModel,
    bp: &BoundedPlane,
    i: usize,
    params: &DecisionParams,
    support: Option<&dyn SurfaceSupport>,
    space: Option<&SensorFrameSpace<'_>>,
) -> Option<(Class, Rule)> {
    let p = frame.points[i].position();
    if let Some(space) = space.filter(|_| params.space_test) {
        match two_hypotheses(space, support, &bp.plane, &p, params) {
            Verdict::Mirror => return Some((Class::Reflection, Rule::RealRefuted)),
            Verdict::Real => return Some((Class::Normal, Rule::MirrorRefuted)),
            Verdict::Open => {}
        }
        if params.seen_surface_test && space.occupancy(&p) == Occupancy::Occupied {
            return Some((Class::Normal, Rule::SeenSurface));
        }
    }
    // A reflection off glass is weak: a return as strong as the landmark's
    // transmitted echoes (a direct return is stronger still) is real.
    if let Some(split) = &bp.echo_split {
        let level = || space.and_then(|s| s.level_incidence_cos(&p));
        let cos = split.incidence_cos(scan, frame, i, level);
        if split.reflected(frame.points[i].intensity, p.coords.norm(), cos) == Some(false) {
            return Some((Class::Normal, Rule::EchoStrength));
        }
    }
    if !params.support_test {
        return None;
    }
    let mirrored = bp.plane.mirror(&p);
    if supports_itself(params, &p, &mirrored) {
        return None;
    }
    let on_beam = returns_along(
        scan,
        sensor,
        frame,
        &mirrored,
        params.free_space_neighbourhood,
    )
    .is_some_and(|(closest, _)| (closest - mirrored.coords.norm()).abs() <= params.support_range);
    let nearby = params.support_radius > 0.0
        && support.is_some_and(|s| s.near(&mirrored, params.support_radius));
    (on_beam || nearby).then_some((Class::Reflection, Rule::PastSeenExtent))
}
