//! The two hypotheses of a point behind a pane, tested against the space
//! seen directly over the sequence: real where it was measured, or the
//! mirror image of a real point in front of the pane.

use nalgebra::Point3;

use super::{DecisionParams, SurfaceSupport};
use crate::classify::boundary::beam_crossing;
use crate::classify::space::{Occupancy, SensorFrameSpace};

/// What the directly seen space says about a behind-plane point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// Only the mirror hypothesis survives: a Reflection.
    Mirror,
    /// Only the real hypothesis survives: an Obstacle seen through glass.
    Real,
    /// Both or neither survive: the frame's own tests decide.
    Open,
}

/// The two hypotheses of point `p` (sensor frame) behind `plane`: real where
/// measured, reached straight through the plane, or the mirror image of a
/// real point reached by reflection at the plane. Each is refuted when its
/// endpoint lies in seen-free space or its leg beyond the crossing runs
/// through a seen surface (tested from `space_margin` off the plane to
/// `space_margin` before the endpoint; clearances and support radius from
/// `params`).
pub(crate) fn two_hypotheses(
    space: &SensorFrameSpace<'_>,
    support: Option<&dyn SurfaceSupport>,
    plane: &crate::geometry::Plane,
    p: &Point3<f64>,
    params: &DecisionParams,
) -> Verdict {
    let (support_radius, margin, clearance_ratio) = (
        params.support_radius,
        params.space_margin,
        params.space_clearance_ratio,
    );
    let range = p.coords.norm();
    let Some(t) = beam_crossing(plane, p) else {
        return Verdict::Open;
    };
    let x = Point3::from(p.coords * (t / range));
    let mirrored = plane.mirror(p);
    let clearance = clearance_ratio * range;
    let refuted = |end: &Point3<f64>| {
        leg_refuted(
            space,
            support,
            &plane.normal,
            &x,
            end,
            (margin, clearance, support_radius),
        )
    };
    // The second hypothesis matters only when the first is refuted, and
    // the other way round: test the cheaper order and stop early.
    if refuted(p) {
        if refuted(&mirrored) {
            Verdict::Open
        } else {
            Verdict::Mirror
        }
    } else if refuted(&mirrored) {
        Verdict::Real
    } else {
        Verdict::Open
    }
}

/// Whether the hypothesis "the echo came from `end`", reached by a leg that
/// leaves the plane (normal `normal`) at `x`, is refuted by the space seen
/// directly: `end` lies in seen-free space with no seen surface within
/// `clearance`, or the leg runs through a seen surface from `margin` off
/// the plane to `margin` before `end`, unless an observed surface lies
/// within `support_radius` of `end`. `(margin, clearance, support_radius)`
/// in metres.
pub(crate) fn leg_refuted(
    space: &SensorFrameSpace<'_>,
    support: Option<&dyn SurfaceSupport>,
    normal: &nalgebra::Vector3<f64>,
    x: &Point3<f64>,
    end: &Point3<f64>,
    (margin, clearance, support_radius): (f64, f64, f64),
) -> bool {
    if space.occupancy_clear_of(end, clearance) == Occupancy::Free {
        return true;
    }
    // Start where the leg is `margin` off the plane: a leg at a grazing
    // angle runs along the frames and wall strips beside the pane.
    let dir = end - x;
    let len = dir.norm();
    if !(len > 0.0) {
        return false;
    }
    let off = normal.dot(&dir).abs() / len;
    let start_t = if off > 1e-9 { margin / off } else { len };
    if start_t + margin >= len {
        return false;
    }
    // A path towards an observed surface is not refuted by a voxel it
    // clips on the way: voxels are coarser than chair legs and desk
    // edges. A path into space nobody saw, through a seen surface, is.
    let start = x + dir * (start_t / len);
    space.blocked(&start, end, margin) && !support.is_some_and(|s| s.near(end, support_radius))
}
