//! Ghost landmarks: reflective planes that are reflections themselves.
//!
//! A wall seen in coated glass appears behind the glass as a plane, and
//! whatever stands farther out shows through it: a surface with returns
//! behind it, which the frontend takes for glass. Fused over the frames, it
//! becomes a reflective landmark, and everything behind it (a building
//! outside the lobby) is then judged against a pane that is not there; with
//! no mirror image of those points in seen-free space it is even taken for
//! a mirror. Such a landmark lies wholly behind the glass that makes it,
//! and its mirror image across that glass lies on a surface seen directly:
//! [`find_ghosts`] finds it so that it can be dropped.

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::reflect::BoundedPlane;

/// Settings of the ghost-landmark test: `[map.ghosts]` switches it; the
/// rest are the method's constants ([`GhostParams::METHOD`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "GhostKeys", into = "GhostKeys")]
pub struct GhostParams {
    /// Drop reflective landmarks found to be reflections of seen surfaces.
    pub enabled: bool,
    /// Share of a landmark's extent whose mirror image across the glass in
    /// front of it must land on a surface seen directly.
    pub min_share: f64,
    /// A ghost lies at least this far behind the glass everywhere, m.
    pub min_depth: f64,
    /// The mirror image lands on a seen surface when one lies within this
    /// distance, m.
    pub radius: f64,
    /// Only the parts of a landmark whose foot on the glass lies within
    /// this distance of the glass's extent are tested, m: a pane's seen
    /// extent ends short of the glass where the ghost stands behind it (its
    /// returns there are the ghost's).
    pub glass_reach: f64,
}

/// The keys of `[map.ghosts]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GhostKeys {
    /// Drop reflective landmarks found to be reflections of seen surfaces.
    enabled: bool,
}

impl From<GhostKeys> for GhostParams {
    fn from(k: GhostKeys) -> Self {
        Self {
            enabled: k.enabled,
            ..Self::METHOD
        }
    }
}

impl From<GhostParams> for GhostKeys {
    fn from(p: GhostParams) -> Self {
        Self { enabled: p.enabled }
    }
}

impl GhostParams {
    /// The test's method: a landmark lying wholly 0.3 m or more behind
    /// another, whose mirror image across it lands within 0.3 m of
    /// surfaces seen directly over at least half of its extent (the parts
    /// whose foot on the glass lies within 5 m of its extent), is a ghost.
    /// Switched off; `configs/default.toml` switches it on.
    pub const METHOD: Self = Self {
        enabled: false,
        min_share: 0.5,
        min_depth: 0.3,
        radius: 0.3,
        glass_reach: 5.0,
    };
}

impl Default for GhostParams {
    /// `[map.ghosts]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("map.ghosts")
    }
}

/// A landmark found to be a reflection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ghost {
    /// Index of the ghost among the planes.
    pub ghost: usize,
    /// Index of the glass it is seen in.
    pub glass: usize,
    /// Share of its extent whose mirror image lands on a seen surface.
    pub share: f64,
}

/// Samples of a plane's reflective extent at most this many.
const MAX_SAMPLES: f64 = 400.0;
/// ... and at least this far apart, m.
const MIN_SPACING: f64 = 0.2;

/// The reflective landmarks among `planes` (world frame) that are
/// reflections of surfaces seen directly (`seen(p, radius)`: a surface lies
/// within `radius` of `p`) in another of them, with that one.
///
/// A landmark is a ghost of glass `g` when it lies wholly at least
/// `min_depth` behind `g` (on the side away from the sensors that saw `g`),
/// the poses of `path` saw it only through `g` (never from beyond `g`'s
/// plane), and, of the samples of its reflective extent whose foot on `g`
/// falls within `glass_reach` of `g`'s extent, at least `min_share` mirror
/// across `g` onto a seen surface. Ghosts are never used as the glass of
/// another ghost.
pub fn find_ghosts(
    planes: &[BoundedPlane],
    path: &[Point3<f64>],
    params: &GhostParams,
    seen: impl Fn(&Point3<f64>, f64) -> bool,
) -> Vec<Ghost> {
    if !params.enabled {
        return Vec::new();
    }
    let samples: Vec<Vec<Point3<f64>>> = planes.iter().map(extent_samples).collect();
    let mut ghosts: Vec<Ghost> = Vec::new();
    for (k, candidate) in samples.iter().enumerate() {
        if candidate.is_empty() {
            continue;
        }
        let best = planes
            .iter()
            .enumerate()
            .filter(|&(g, glass)| g != k && seen_through(&planes[k], glass, path, params))
            .filter_map(|(g, glass)| {
                let share = mirrored_share(candidate, glass, params, &seen)?;
                tracing::debug!(plane = k, glass = g, share, "ghost test");
                (share >= params.min_share).then_some(Ghost {
                    ghost: k,
                    glass: g,
                    share,
                })
            })
            .max_by(|a, b| a.share.total_cmp(&b.share));
        ghosts.extend(best);
    }
    // A ghost does not make ghosts: keep only those whose glass is real.
    let is_ghost = |i: usize| ghosts.iter().any(|g| g.ghost == i);
    ghosts
        .iter()
        .copied()
        .filter(|g| !is_ghost(g.glass))
        .collect()
}

/// Poses of the path tried as the sensor that saw a ghost through glass,
/// at most.
const MAX_POSES: usize = 1000;

/// Whether `candidate` was seen only through `glass` from the poses of
/// `path`: some pose stands in front of both, its line of sight to the
/// candidate's centre crossing the glass within `glass_reach` of its
/// extent, and no pose in front of the candidate stands behind the glass's
/// plane. A pane seen from the far side of the glass, or from between the
/// two, is real wherever its mirror image lands (in a building laid out
/// symmetrically about a glass door, on a wall).
fn seen_through(
    candidate: &BoundedPlane,
    glass: &BoundedPlane,
    path: &[Point3<f64>],
    params: &GhostParams,
) -> bool {
    let Some(centre) = candidate.boundary.centroid() else {
        return false;
    };
    let centre = candidate.chart.to_3d(&centre);
    let step = path.len().div_ceil(MAX_POSES).max(1);
    let poses = || path.iter().step_by(step);
    // Seen from beyond the glass's plane: a real pane behind it, seen
    // directly as well (a facade at the end of a corridor with a glass
    // door across it).
    let seen_directly = poses()
        .any(|s| candidate.plane.signed_distance(s) > 0.0 && glass.plane.signed_distance(s) < 0.0);
    !seen_directly
        && poses().any(|s| {
            let (in_front, behind) = (
                glass.plane.signed_distance(s),
                glass.plane.signed_distance(&centre),
            );
            if !(in_front > 0.0 && behind < 0.0 && candidate.plane.signed_distance(s) > 0.0) {
                return false;
            }
            let crossing = s + (centre - s) * (in_front / (in_front - behind));
            glass.bounds(&crossing, params.glass_reach)
        })
}

/// Points of the plane's reflective extent on a grid (world frame), over
/// the box of its boundary (the hull of what was observed), not of its
/// panes: a pane's fitted edge may overreach the observations towards the
/// glass that makes the ghost, and would then fail the depth test.
fn extent_samples(plane: &BoundedPlane) -> Vec<Point3<f64>> {
    let vertices = plane.boundary.vertices();
    if vertices.len() < 3 {
        return Vec::new();
    }
    let (mut lo, mut hi) = (vertices[0], vertices[0]);
    for v in vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let spacing = (plane.boundary.area() / MAX_SAMPLES)
        .sqrt()
        .max(MIN_SPACING);
    let mut out = Vec::new();
    let mut u = lo.x + 0.5 * spacing;
    while u < hi.x {
        let mut v = lo.y + 0.5 * spacing;
        while v < hi.y {
            let uv = Point2::new(u, v);
            if plane.bounds_2d(&uv, 0.0) {
                out.push(plane.chart.to_3d(&uv));
            }
            v += spacing;
        }
        u += spacing;
    }
    out
}

/// The share of `samples` mirrored across `glass` onto a seen surface,
/// among those whose foot falls within the glass's extent; `None` when the
/// samples do not all lie `min_depth` behind the glass or none has its
/// foot on it.
fn mirrored_share(
    samples: &[Point3<f64>],
    glass: &BoundedPlane,
    params: &GhostParams,
    seen: impl Fn(&Point3<f64>, f64) -> bool,
) -> Option<f64> {
    let plane = &glass.plane;
    if samples
        .iter()
        .any(|x| plane.signed_distance(x) > -params.min_depth)
    {
        return None;
    }
    let (mut facing, mut landed) = (0usize, 0usize);
    for x in samples {
        if !glass.bounds(&plane.project(x), params.glass_reach) {
            continue;
        }
        facing += 1;
        landed += usize::from(seen(&plane.mirror(x), params.radius));
    }
    (facing > 0).then(|| landed as f64 / facing as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;
    use nalgebra::Vector3;

    /// A 4 m × 3 m vertical pane on the plane `normal · x + d = 0`, centred
    /// at `centre`.
    fn pane(normal: Vector3<f64>, d: f64, centre: Point3<f64>) -> BoundedPlane {
        let plane = Plane::new(normal, d).expect("a plane");
        let along = Vector3::z().cross(&plane.normal).normalize();
        let corners = [(-2.0, 0.0), (2.0, 0.0), (2.0, 3.0), (-2.0, 3.0)]
            .map(|(a, z)| centre + along * a + Vector3::z() * z);
        BoundedPlane::from_points(plane, corners)
    }

    /// The test on, with its default thresholds.
    fn switched_on() -> GhostParams {
        GhostParams {
            enabled: true,
            ..GhostParams::METHOD
        }
    }

    /// A wall at x = -3 seen directly: within `r` of it.
    fn wall_seen(p: &Point3<f64>, r: f64) -> bool {
        (p.x + 3.0).abs() <= r && p.y.abs() <= 3.0 && (0.0..=3.0).contains(&p.z)
    }

    /// Glass at x = 2 facing the sensors at the origin; the wall at x = -3
    /// mirrors across it to x = 7. A landmark at x = 7 is that wall's
    /// ghost; one at x = 5 (real glass behind the glass, its mirror image
    /// in open space at x = -1) is not, nor is anything with the test off.
    #[test]
    fn a_plane_where_a_seen_wall_mirrors_is_a_ghost() {
        let glass = pane(-Vector3::x(), 2.0, Point3::new(2.0, 0.0, 0.0));
        let ghost = pane(-Vector3::x(), 7.0, Point3::new(7.0, 0.0, 0.0));
        let real = pane(-Vector3::x(), 5.0, Point3::new(5.0, 0.0, 0.0));
        let on = switched_on();
        let path = [Point3::origin()];
        let found = find_ghosts(
            &[glass.clone(), ghost.clone(), real.clone()],
            &path,
            &on,
            wall_seen,
        );
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].ghost, found[0].glass), (1, 0));
        assert!(found[0].share > 0.95, "{found:?}");
        assert!(find_ghosts(
            &[glass, ghost, real],
            &path,
            &GhostParams::METHOD,
            wall_seen
        )
        .is_empty());
    }

    /// A plane not wholly behind the glass (crossing it, or in front of
    /// it) is never a ghost of it, whatever lies at its mirror image.
    #[test]
    fn a_plane_not_behind_the_glass_is_no_ghost_of_it() {
        let glass = pane(-Vector3::x(), 2.0, Point3::new(2.0, 0.0, 0.0));
        let side = pane(Vector3::y(), 0.0, Point3::new(2.0, 0.0, 0.0));
        let on = switched_on();
        let everywhere = |_: &Point3<f64>, _: f64| true;
        let found = find_ghosts(&[glass, side], &[Point3::origin()], &on, everywhere);
        assert!(found.is_empty(), "{found:?}");
    }

    /// The same plane facing away from the glass (seen from beyond it, not
    /// through the glass: a building laid out symmetrically about a glass
    /// door) is no ghost, though its mirror image lands on the wall.
    #[test]
    fn a_plane_seen_from_beyond_is_no_ghost() {
        let glass = pane(-Vector3::x(), 2.0, Point3::new(2.0, 0.0, 0.0));
        let facing_away = pane(Vector3::x(), -7.0, Point3::new(7.0, 0.0, 0.0));
        let on = switched_on();
        let path = [Point3::origin(), Point3::new(10.0, 0.0, 1.0)];
        let found = find_ghosts(&[glass, facing_away], &path, &on, wall_seen);
        assert!(found.is_empty(), "{found:?}");
    }

    /// A plane also seen from between the glass and itself (a facade at
    /// the end of a corridor, seen through a glass door across it and,
    /// past the door, directly) is real, though its mirror image across
    /// the glass lands on a wall.
    #[test]
    fn a_plane_also_seen_directly_is_no_ghost() {
        let glass = pane(-Vector3::x(), 2.0, Point3::new(2.0, 0.0, 0.0));
        let facade = pane(-Vector3::x(), 7.0, Point3::new(7.0, 0.0, 0.0));
        let on = switched_on();
        let through_only = [Point3::origin()];
        let found = find_ghosts(
            &[glass.clone(), facade.clone()],
            &through_only,
            &on,
            wall_seen,
        );
        assert_eq!(found.len(), 1, "{found:?}");
        let also_past_the_door = [Point3::origin(), Point3::new(5.0, 0.0, 1.0)];
        let found = find_ghosts(&[glass, facade], &also_past_the_door, &on, wall_seen);
        assert!(found.is_empty(), "{found:?}");
    }
}
