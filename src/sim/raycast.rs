//! Ray casting against the scene.
//!
//! Surfaces are cut into small convex pieces ("patches"): a convex
//! quadrilateral (most surfaces: walls, floors, box sides) stays one quad,
//! split into a grid when it is large; any other polygon is triangulated and
//! large triangles are split. The patches are indexed by a parry `Bvh` over
//! their bounding boxes. Nodes are tested with a slab test on the ray's
//! inverse direction, patches with a plane intersection and an inside test
//! against their edges. Each patch remembers its surface.
//!
//! Keeping quads whole matters: the two triangles of an axis-aligned
//! rectangle have the same bounding box as the rectangle, so every ray
//! entering it would test both.

use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhNode};

use super::surface::Surface;

/// Hits closer than this to the ray origin are ignored (the surface a ray
/// leaves from), metres.
pub const MIN_HIT_DISTANCE: f64 = 1e-7;

/// Patches are split until no edge is longer than this, metres: large
/// polygons (outdoor ground, long facades) would otherwise have bounding
/// boxes that most rays enter. (10 m: 20 % faster on the lobby scene than no
/// splitting; 3 m makes the tree so large that every scene gets slower.)
const MAX_EDGE: f64 = 10.0;
/// At most `2^MAX_SPLIT_DEPTH` pieces per triangle, however large.
const MAX_SPLIT_DEPTH: u32 = 10;
/// At most this many rows (and columns) of pieces per quad.
const MAX_GRID: usize = 64;
/// A point this far outside a patch edge (metres) still hits it, so that
/// adjacent patches leave no cracks.
const EDGE_TOLERANCE: f64 = 1e-9;

/// A convex planar patch (triangle or quad) prepared for intersection tests.
#[derive(Debug, Clone, Copy)]
struct Patch {
    /// Vertices (the fourth repeats the third for a triangle).
    v: [DVec3; 4],
    /// Unit in-plane normals of the edges `v[i] → v[i+1]`, pointing inwards.
    inward: [DVec3; 4],
    /// Number of vertices, 3 or 4.
    n: usize,
    /// Unit plane normal.
    normal: DVec3,
    /// Plane offset `normal·x + d = 0`.
    d: f64,
    surface: u32,
}

impl Patch {
    /// A patch from 3 or 4 coplanar vertices in convex order (either
    /// orientation); `None` when degenerate.
    fn new(vertices: &[DVec3], surface: u32) -> Option<Self> {
        let n = vertices.len();
        debug_assert!(n == 3 || n == 4);
        let mut normal = DVec3::ZERO;
        for i in 0..n {
            normal += vertices[i].cross(vertices[(i + 1) % n]);
        }
        let normal = normal.try_normalize()?;
        let mut v = [vertices[n - 1]; 4];
        v[..n].copy_from_slice(vertices);
        let mut inward = [DVec3::ZERO; 4];
        for i in 0..n {
            inward[i] = normal.cross(v[(i + 1) % n] - v[i]).try_normalize()?;
        }
        Some(Self {
            v,
            inward,
            n,
            normal,
            d: -normal.dot(v[0]),
            surface,
        })
    }

    fn aabb(&self) -> Aabb {
        let pad = DVec3::splat(1e-6);
        let lo = self.v.iter().fold(DVec3::INFINITY, |a, p| a.min(*p));
        let hi = self.v.iter().fold(DVec3::NEG_INFINITY, |a, p| a.max(*p));
        Aabb::new(lo - pad, hi + pad)
    }

    /// Distance along the ray to the patch (two-sided), if it is hit.
    #[inline]
    fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let denom = self.normal.dot(dir);
        if denom.abs() < 1e-14 {
            return None;
        }
        let t = -(self.normal.dot(origin) + self.d) / denom;
        if !(t > MIN_HIT_DISTANCE) {
            return None;
        }
        let p = origin + dir * t;
        for i in 0..self.n {
            if self.inward[i].dot(p - self.v[i]) < -EDGE_TOLERANCE {
                return None;
            }
        }
        Some(t)
    }

    /// Euclidean distance from `p` to the patch (its plane inside the
    /// edges, else the nearest edge).
    fn distance(&self, p: DVec3) -> f64 {
        let off = self.normal.dot(p) + self.d;
        let q = p - self.normal * off;
        if (0..self.n).all(|i| self.inward[i].dot(q - self.v[i]) >= 0.0) {
            return off.abs();
        }
        (0..self.n)
            .map(|i| segment_distance(p, self.v[i], self.v[(i + 1) % self.n]))
            .fold(f64::INFINITY, f64::min)
    }

    fn area(&self) -> f64 {
        let mut s = DVec3::ZERO;
        for i in 0..self.n {
            s += self.v[i].cross(self.v[(i + 1) % self.n]);
        }
        0.5 * s.length()
    }
}

/// The nearest surface along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f64,
    /// Index of the surface hit.
    pub surface: u32,
}

/// A bounding-volume hierarchy over the surfaces of a scene, cut into
/// convex patches.
pub struct SceneIndex {
    bvh: Bvh,
    patches: Vec<Patch>,
}

impl std::fmt::Debug for SceneIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneIndex")
            .field("patches", &self.patches.len())
            .finish()
    }
}

impl SceneIndex {
    /// Cut the surfaces into patches and build the hierarchy. Surfaces that
    /// cannot be triangulated were rejected when the scene was built, so
    /// they are skipped here.
    pub fn new(surfaces: &[Surface]) -> Self {
        let mut patches = Vec::new();
        for (i, s) in surfaces.iter().enumerate() {
            let id = i as u32;
            let mut push = |v: &[DVec3]| patches.extend(Patch::new(v, id));
            if s.vertices.len() == 4 && is_convex(s) {
                quad_grid(&s.vertices, &mut push);
            } else {
                for tri in s.triangles().unwrap_or_default() {
                    split(tri, MAX_SPLIT_DEPTH, &mut |t| push(&t));
                }
            }
        }
        let boxes: Vec<Aabb> = patches.iter().map(Patch::aabb).collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
        Self { bvh, patches }
    }

    /// Number of patches (the leaves of the hierarchy).
    pub fn patch_count(&self) -> usize {
        self.patches.len()
    }

    /// Total area of the patches of `surface`, m² (equals the surface's
    /// area: patches tile it).
    pub fn patch_area(&self, surface: u32) -> f64 {
        self.patches
            .iter()
            .filter(|p| p.surface == surface)
            .map(Patch::area)
            .sum()
    }

    /// The nearest hit of the ray `origin + t·dir` (unit `dir`) with
    /// `MIN_HIT_DISTANCE < t < max_t`, ignoring the surface `skip` (the one
    /// the ray leaves from).
    ///
    /// Nodes are tested with a slab test on the precomputed inverse
    /// direction (parry's generic AABB ray cast divides per node and is
    /// about three times slower here).
    #[inline]
    pub fn cast(&self, origin: DVec3, dir: DVec3, max_t: f64, skip: Option<u32>) -> Option<Hit> {
        let inv = dir.recip();
        let skip = skip.unwrap_or(u32::MAX);
        self.bvh
            .find_best(
                max_t,
                |node: &BvhNode, _best| {
                    let t1 = (node.mins() - origin) * inv;
                    let t2 = (node.maxs() - origin) * inv;
                    let near = t1.min(t2).max_element().max(0.0);
                    let far = t1.max(t2).min_element();
                    if far >= near {
                        near
                    } else {
                        f64::MAX
                    }
                },
                |leaf, best| {
                    let patch = &self.patches[leaf as usize];
                    if patch.surface == skip {
                        return None;
                    }
                    patch.intersect(origin, dir).filter(|&t| t < best)
                },
            )
            .map(|(leaf, t)| Hit {
                t,
                surface: self.patches[leaf as usize].surface,
            })
    }

    /// The distance from `p` to the nearest surface, when it is below
    /// `radius` metres (`None` when no surface is that close).
    pub fn distance_within(&self, p: DVec3, radius: f64) -> Option<f64> {
        self.bvh
            .find_best(
                radius,
                |node: &BvhNode, _best| {
                    let outside = (node.mins() - p).max(p - node.maxs()).max(DVec3::ZERO);
                    outside.length()
                },
                |leaf, best| {
                    let d = self.patches[leaf as usize].distance(p);
                    (d < best).then_some(d)
                },
            )
            .map(|(_, d)| d)
    }
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * s)
}

/// Whether a 4-vertex surface is a convex quadrilateral.
fn is_convex(s: &Surface) -> bool {
    let v = &s.vertices;
    (0..4).all(|i| {
        let a = v[i];
        let b = v[(i + 1) % 4];
        let c = v[(i + 2) % 4];
        (b - a).cross(c - b).dot(s.normal) > 1e-12
    })
}

/// Cut a convex planar quad into a grid of quads no longer than
/// [`MAX_EDGE`] (bilinear subdivision keeps them planar and convex).
fn quad_grid(q: &[DVec3], out: &mut impl FnMut(&[DVec3])) {
    let cells = |a: f64, b: f64| ((a.max(b) / MAX_EDGE).ceil() as usize).clamp(1, MAX_GRID);
    let nu = cells(q[0].distance(q[1]), q[3].distance(q[2]));
    let nv = cells(q[0].distance(q[3]), q[1].distance(q[2]));
    if nu == 1 && nv == 1 {
        out(q);
        return;
    }
    let at = |i: usize, j: usize| {
        let (u, v) = (i as f64 / nu as f64, j as f64 / nv as f64);
        q[0] * ((1.0 - u) * (1.0 - v))
            + q[1] * (u * (1.0 - v))
            + q[2] * (u * v)
            + q[3] * ((1.0 - u) * v)
    };
    for i in 0..nu {
        for j in 0..nv {
            out(&[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
}

/// Split a triangle at the midpoint of its longest edge until every edge
/// is at most [`MAX_EDGE`] long (or `depth` splits are used up).
fn split(t: [DVec3; 3], depth: u32, out: &mut impl FnMut([DVec3; 3])) {
    let [a, b, c] = t;
    let (ab, bc, ca) = (a.distance(b), b.distance(c), c.distance(a));
    let longest = ab.max(bc).max(ca);
    if longest <= MAX_EDGE || depth == 0 {
        out(t);
    } else if longest == ab {
        let m = (a + b) * 0.5;
        split([a, m, c], depth - 1, out);
        split([m, b, c], depth - 1, out);
    } else if longest == bc {
        let m = (b + c) * 0.5;
        split([a, b, m], depth - 1, out);
        split([a, m, c], depth - 1, out);
    } else {
        let m = (c + a) * 0.5;
        split([a, b, m], depth - 1, out);
        split([m, b, c], depth - 1, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: f64, material: usize) -> Surface {
        Surface::new(
            vec![
                DVec3::new(-1.0, -1.0, z),
                DVec3::new(1.0, -1.0, z),
                DVec3::new(1.0, 1.0, z),
                DVec3::new(-1.0, 1.0, z),
            ],
            material,
            "sq".into(),
        )
        .unwrap()
    }

    #[test]
    fn large_surfaces_are_tiled_without_gaps() {
        let ground = Surface::new(
            vec![
                DVec3::new(-50.0, -20.0, 0.0),
                DVec3::new(50.0, -20.0, 0.0),
                DVec3::new(50.0, 20.0, 0.0),
                DVec3::new(-50.0, 20.0, 0.0),
            ],
            0,
            "ground".into(),
        )
        .unwrap();
        // A large non-convex polygon (an L) goes through triangulation.
        let l = Surface::new(
            [
                (0.0, 0.0),
                (40.0, 0.0),
                (40.0, 10.0),
                (10.0, 10.0),
                (10.0, 30.0),
                (0.0, 30.0),
            ]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 3.0))
            .collect(),
            0,
            "l".into(),
        )
        .unwrap();
        let idx = SceneIndex::new(&[ground.clone(), l.clone()]);
        assert_eq!(
            idx.patches.iter().filter(|p| p.surface == 0).count(),
            10 * 4
        );
        assert!((idx.patch_area(0) - ground.area()).abs() < 1e-6);
        assert!((idx.patch_area(1) - l.area()).abs() < 1e-6);
        for p in &idx.patches {
            for i in 0..p.n {
                assert!(p.v[i].distance(p.v[(i + 1) % p.n]) <= MAX_EDGE + 1e-9);
            }
        }
        // Every point is hit exactly once from above, seams included.
        for i in 0..400 {
            let x = -49.95 + 99.9 * i as f64 / 399.0;
            let y = -19.95 + 39.9 * ((i * 37) % 400) as f64 / 399.0;
            let h = idx
                .cast(DVec3::new(x, y, -5.0), DVec3::Z, 6.0, None)
                .unwrap();
            assert_eq!(h.surface, 0);
            assert!((h.t - 5.0).abs() < 1e-12);
        }
        for x in [0.0, 10.0, 20.0, 30.0, 39.999] {
            let h = idx
                .cast(DVec3::new(x, 5.0, 10.0), -DVec3::Z, 100.0, None)
                .unwrap();
            assert_eq!(h.surface, 1, "x = {x}");
        }
        assert!(idx
            .cast(DVec3::new(20.0, 20.0, 10.0), -DVec3::Z, 6.99, None)
            .is_none());
    }

    #[test]
    fn nearest_hit_skip_and_range_limit() {
        let idx = SceneIndex::new(&[square(2.0, 0), square(5.0, 0)]);
        assert_eq!(idx.patch_count(), 2);
        let h = idx.cast(DVec3::ZERO, DVec3::Z, 100.0, None).unwrap();
        assert_eq!(h.surface, 0);
        assert!((h.t - 2.0).abs() < 1e-12);
        let h = idx.cast(DVec3::ZERO, DVec3::Z, 100.0, Some(0)).unwrap();
        assert_eq!(h.surface, 1);
        assert!(idx.cast(DVec3::ZERO, DVec3::Z, 1.5, None).is_none());
        assert!(idx.cast(DVec3::ZERO, -DVec3::Z, 100.0, None).is_none());
        // Axis-parallel rays (infinite inverse direction components).
        let h = idx
            .cast(DVec3::new(0.5, 0.5, 0.0), DVec3::Z, 100.0, None)
            .unwrap();
        assert!((h.t - 2.0).abs() < 1e-12);
        // Outside the squares.
        let d = DVec3::new(1.0, 0.0, 1.0).normalize();
        assert!(idx.cast(DVec3::ZERO, d, 100.0, None).is_none());
        // From behind (two-sided).
        let h = idx
            .cast(DVec3::new(0.3, 0.2, 9.0), -DVec3::Z, 100.0, None)
            .unwrap();
        assert_eq!(h.surface, 1);
    }

    #[test]
    fn distance_to_the_nearest_surface() {
        let idx = SceneIndex::new(&[square(2.0, 0), square(5.0, 0)]);
        let near = |p: DVec3, r: f64| idx.distance_within(p, r);
        // Above the inside of a square: the distance to its plane.
        assert!((near(DVec3::new(0.2, 0.3, 2.1), 1.0).unwrap() - 0.1).abs() < 1e-12);
        assert!((near(DVec3::new(0.2, 0.3, 4.0), 1.5).unwrap() - 1.0).abs() < 1e-12);
        // Beside a square: the distance to its edge.
        let d = near(DVec3::new(1.3, 0.0, 2.4), 1.0).unwrap();
        assert!((d - 0.5).abs() < 1e-12, "{d}");
        // Nothing within the radius.
        assert!(near(DVec3::new(0.0, 0.0, 3.5), 1.0).is_none());
        assert!(near(DVec3::new(3.0, 0.0, 2.0), 1.5).is_none());
    }
}
