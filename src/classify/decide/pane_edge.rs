//! Beams that crossed a landmark near its extent's edge
//! ([`DecisionParams::pane_edge_margin`]): they may have passed beside it.

use nalgebra::Point3;

use super::hypotheses::{two_hypotheses, Verdict};
use super::{DecisionParams, SurfaceSupport};
use crate::classify::rule::Rule;
use crate::classify::space::{Occupancy, SensorFrameSpace};
use crate::reflect::BoundedPlane;

/// Whether the beam towards `p`, crossing `bp` at range `t`, crossed it
/// within `margin` of its extent's edge ([`DecisionParams::pane_edge_margin`];
/// never with `margin` 0).
pub(crate) fn near_pane_edge(bp: &BoundedPlane, p: &Point3<f64>, t: f64, margin: f64) -> bool {
    margin > 0.0 && !bp.bounds(&Point3::from(p.coords * (t / p.coords.norm())), -margin)
}

/// The rule by which the space seen directly says behind-plane point `p`
/// is real where it was measured: its mirror image refuted
/// ([`two_hypotheses`]), or a surface seen there (the seen-surface test).
/// `None` without that evidence.
pub(super) fn real_by_space(
    space: Option<&SensorFrameSpace<'_>>,
    support: Option<&dyn SurfaceSupport>,
    bp: &BoundedPlane,
    p: &Point3<f64>,
    params: &DecisionParams,
) -> Option<Rule> {
    let space = space.filter(|_| params.space_test)?;
    if two_hypotheses(space, support, &bp.plane, p, params) == Verdict::Real {
        return Some(Rule::MirrorRefuted);
    }
    (params.seen_surface_test && space.occupancy(p) == Occupancy::Occupied)
        .then_some(Rule::SeenSurface)
}
