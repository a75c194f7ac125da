//! The ground-truth reflective planes of a scene, as `planes.json` records.
//!
//! Reflective surfaces (glass, mirror, other reflective) of the same class
//! that lie on one plane (a window wall of several panes between mullions)
//! form one landmark: its `hull` is the convex hull of all panes and `panes`
//! lists each pane. The normal is oriented towards the trajectory: the side
//! from which the sensor sees the plane. `observations` counts the frames in
//! which at least one return is a surface echo of the plane.

use glam::DVec3;
use nalgebra::Point2;

use super::echo::label;
use super::material::MaterialKind;
use super::raycast::SceneIndex;
use super::scene::Scene;
use super::simulator::SimFrame;
use crate::geometry::ConvexPolygon;
use crate::io::{PlaneKind, PlaneRecord};

/// Two surfaces are on one plane when their normals agree to this cosine...
const COPLANAR_COS: f64 = 1.0 - 1e-9;
/// ... and their offsets to this distance, metres.
const COPLANAR_D: f64 = 1e-4;

/// A group of coplanar reflective surfaces of one class.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneGroup {
    /// Material class.
    pub kind: MaterialKind,
    /// Surface indices (panes).
    pub surfaces: Vec<u32>,
    /// Unit normal, facing the trajectory.
    pub normal: DVec3,
    /// Offset of `normal·x + d = 0`.
    pub d: f64,
}

/// The reflective planes of a scene and which surface belongs to which.
#[derive(Debug, Clone, PartialEq)]
pub struct TruePlanes {
    /// The groups, in order of their first surface.
    pub groups: Vec<PlaneGroup>,
    /// Group of each surface (`None` for diffuse surfaces).
    pub group_of: Vec<Option<usize>>,
}

impl TruePlanes {
    /// Group the reflective surfaces of `scene` and orient each group
    /// towards the trajectory.
    ///
    /// Orientation is decided by line of sight: trajectory points (every
    /// ~0.25 m) that see a pane directly vote for the side they are on. A
    /// group no trajectory point sees faces the nearest trajectory point
    /// off its plane.
    pub fn of(scene: &Scene) -> Self {
        let samples = trajectory_samples(scene);
        let mut groups: Vec<PlaneGroup> = Vec::new();
        let mut group_of = vec![None; scene.surfaces.len()];
        for (i, s) in scene.surfaces.iter().enumerate() {
            let kind = scene.material_of(s).kind;
            if !kind.is_reflective() {
                continue;
            }
            let found = groups.iter().position(|g| {
                let c = g.normal.dot(s.normal);
                g.kind == kind
                    && c.abs() >= COPLANAR_COS
                    && (g.d - c.signum() * s.d).abs() <= COPLANAR_D
            });
            let gi = found.unwrap_or_else(|| {
                groups.push(PlaneGroup {
                    kind,
                    surfaces: Vec::new(),
                    normal: s.normal,
                    d: s.d,
                });
                groups.len() - 1
            });
            groups[gi].surfaces.push(i as u32);
            group_of[i] = Some(gi);
        }
        if !groups.is_empty() {
            let index = SceneIndex::new(&scene.surfaces);
            for g in &mut groups {
                if orientation(scene, &index, g, &samples) < 0.0 {
                    g.normal = -g.normal;
                    g.d = -g.d;
                }
            }
        }
        Self { groups, group_of }
    }

    /// The groups whose surface echo appears in a frame (sorted, unique),
    /// by the physical truth of its points.
    pub fn observed_in(&self, frame: &SimFrame) -> Vec<usize> {
        let mut seen: Vec<usize> = frame
            .frame
            .points
            .iter()
            .zip(&frame.truth)
            .filter(|(_, t)| {
                matches!(
                    t.physical,
                    label::GLASS | label::MIRROR | label::OTHER_REFLECTIVE
                )
            })
            .filter_map(|(_, t)| self.group_of.get(t.surface as usize).copied().flatten())
            .collect();
        seen.sort_unstable();
        seen.dedup();
        seen
    }

    /// `planes.json` records; `tally` gives the observations per group (see
    /// [`PlaneTally`]) and `frame_name` names frame `k`.
    pub fn records(
        &self,
        scene: &Scene,
        tally: &PlaneTally,
        frame_name: impl Fn(usize) -> String,
    ) -> Vec<PlaneRecord> {
        self.groups
            .iter()
            .enumerate()
            .map(|(id, g)| {
                let oriented = |i: u32| -> Vec<DVec3> {
                    let s = &scene.surfaces[i as usize];
                    let mut v = s.vertices.clone();
                    if s.normal.dot(g.normal) < 0.0 {
                        v.reverse();
                    }
                    v
                };
                let to3 = |v: &[DVec3]| v.iter().map(|p| p.to_array()).collect::<Vec<_>>();
                let (hull, panes) = if g.surfaces.len() == 1 {
                    (to3(&oriented(g.surfaces[0])), Vec::new())
                } else {
                    let panes: Vec<Vec<DVec3>> = g.surfaces.iter().map(|&i| oriented(i)).collect();
                    (
                        to3(&hull_on_plane(g, panes.iter().flatten())),
                        panes.iter().map(|p| to3(p)).collect(),
                    )
                };
                let (count, first, last) = tally.get(id);
                PlaneRecord {
                    id,
                    kind: PlaneKind::Reflective,
                    material: Some(g.kind.name().to_string()),
                    normal: g.normal.to_array(),
                    d: g.d,
                    hull,
                    observations: count,
                    first_frame: first.map(&frame_name),
                    last_frame: last.map(&frame_name),
                    panes,
                    mirror_probability: None,
                    reflection_share: None,
                    decided_share: None,
                }
            })
            .collect()
    }
}

/// +1 when the trajectory sees the group from the side its current normal
/// points to, -1 when from the other side.
fn orientation(scene: &Scene, index: &SceneIndex, g: &PlaneGroup, samples: &[DVec3]) -> f64 {
    let side = |p: DVec3| g.normal.dot(p) + g.d;
    let mut votes = 0i64;
    for &i in &g.surfaces {
        let s = &scene.surfaces[i as usize];
        let centre = s.center();
        // The centre and the vertices pulled a fifth of the way inwards.
        let probes: Vec<DVec3> = std::iter::once(centre)
            .chain(s.vertices.iter().take(8).map(|v| *v + (centre - *v) * 0.2))
            .collect();
        for &o in samples {
            let sd = side(o);
            if sd.abs() < 1e-6 {
                continue;
            }
            for &p in &probes {
                let dist = o.distance(p);
                if dist < 1e-6 {
                    continue;
                }
                let hit = index.cast(o, (p - o) / dist, dist + 1e-6, None);
                if hit.is_some_and(|h| h.surface == i && (h.t - dist).abs() < 1e-6) {
                    votes += if sd > 0.0 { 1 } else { -1 };
                }
            }
        }
    }
    if votes != 0 {
        return votes.signum() as f64;
    }
    // Nobody sees it: face the nearest trajectory point off the plane.
    let centre = scene.surfaces[g.surfaces[0] as usize].center();
    samples
        .iter()
        .filter(|o| side(**o).abs() >= 1e-6)
        .min_by(|a, b| {
            a.distance_squared(centre)
                .total_cmp(&b.distance_squared(centre))
        })
        .map_or(1.0, |o| side(*o).signum())
}

/// Convex hull of points on a group's plane, counter-clockwise seen from its
/// normal.
fn hull_on_plane<'a>(g: &PlaneGroup, points: impl Iterator<Item = &'a DVec3>) -> Vec<DVec3> {
    let n = g.normal;
    let helper = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    let u = helper.cross(n).normalize();
    let v = n.cross(u);
    let origin = -n * g.d;
    let pts: Vec<Point2<f64>> = points
        .map(|p| Point2::new((*p - origin).dot(u), (*p - origin).dot(v)))
        .collect();
    ConvexPolygon::hull(&pts)
        .vertices()
        .iter()
        .map(|q| origin + u * q.x + v * q.y)
        .collect()
}

/// Positions along the trajectory every ~0.25 m (one lap / one pass).
fn trajectory_samples(scene: &Scene) -> Vec<DVec3> {
    let t = &scene.trajectory;
    let n = ((t.length() / 0.25).ceil() as usize).clamp(2, 100_000);
    (0..=n)
        .map(|i| t.position(t.length() * i as f64 / n as f64))
        .collect()
}

/// Observation counts per plane group: frames seen, first and last frame
/// index. Tallies of disjoint frame sets combine with [`PlaneTally::merge`]
/// in any order with the same result.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlaneTally {
    entries: Vec<(usize, Option<usize>, Option<usize>)>,
}

impl PlaneTally {
    /// Record that frame `k` observed `groups`.
    pub fn add(&mut self, k: usize, groups: &[usize]) {
        for &g in groups {
            if self.entries.len() <= g {
                self.entries.resize(g + 1, (0, None, None));
            }
            let e = &mut self.entries[g];
            e.0 += 1;
            e.1 = Some(e.1.map_or(k, |f| f.min(k)));
            e.2 = Some(e.2.map_or(k, |l| l.max(k)));
        }
    }

    /// Combine two tallies of disjoint frame sets.
    pub fn merge(mut self, other: Self) -> Self {
        if self.entries.len() < other.entries.len() {
            self.entries.resize(other.entries.len(), (0, None, None));
        }
        for (g, o) in other.entries.into_iter().enumerate() {
            let e = &mut self.entries[g];
            e.0 += o.0;
            e.1 = match (e.1, o.1) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            e.2 = match (e.2, o.2) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
        }
        self
    }

    /// (frames observed, first frame, last frame) of group `g`.
    pub fn get(&self, g: usize) -> (usize, Option<usize>, Option<usize>) {
        self.entries.get(g).copied().unwrap_or((0, None, None))
    }
}
