//! Echo strength for beams that crossed more than one pane, decided pane by
//! pane along the beam.

use nalgebra::Point3;

use super::DecisionParams;
use crate::classify::boundary::BeamPlanes;
use crate::reflect::echo_split::EchoSplit;
use crate::reflect::BoundedPlane;

/// Echo strength for a beam that crossed pane `first` (at range `t`) and
/// then a second pane before its return at `p`, recursively: a weak echo by
/// the first pane's split is a reflection off it; a strong one crossed it,
/// and the second pane decides as if it were the first (behind a mirror
/// nothing is real; its own split, or the next pane's, tells a reflection
/// off it from an echo through it). `None` where a pane on the way has no
/// split, or the strength falls in a split's undecided band.
pub(super) fn past_second_pane(
    bounded: &[BoundedPlane],
    beams: &BeamPlanes<'_>,
    first: usize,
    p: &Point3<f64>,
    t: f64,
    params: &DecisionParams,
    strength: impl Fn(&EchoSplit) -> Option<bool>,
) -> Option<bool> {
    let range = p.coords.norm();
    let (mut pane, mut at) = (first, t);
    // At most as many panes as the map has: each step moves farther along.
    for _ in 0..bounded.len() {
        if strength(&bounded[pane].echo_split?)? {
            return Some(true);
        }
        let Some((next, t_next)) = beams.nearest_between(
            p,
            pane,
            at + params.glass_distance,
            range - params.behind_distance,
        ) else {
            // Transmitted by the last pane before the return: real.
            return Some(false);
        };
        if bounded[next].is_mirror() {
            return Some(true);
        }
        (pane, at) = (next, t_next);
    }
    None
}
