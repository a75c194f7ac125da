//! Convex polygons in a plane chart: reflective-plane boundaries.
//!
//! Everything is built on one robust primitive, Andrew's monotone chain
//! ([`ConvexPolygon::hull`]), which drops non-finite, repeated and
//! (near-)collinear points; every operation that produces a polygon ends by
//! re-hulling its result, so outputs are always strictly convex and CCW, or
//! empty. No operation panics on degenerate input.

use std::cmp::Ordering;

use nalgebra::{Point2, Vector2};

/// Relative tolerance of the hull's turn test: a vertex is kept only when it
/// lies more than `HULL_EPS · (extent + magnitude)` to the left of the chord
/// joining its neighbours (`extent`: bounding-box size, `magnitude`: largest
/// absolute coordinate). This removes collinear and duplicate vertices whose
/// coordinates carry round-off (≈ 500 ulps of the coordinates) while any
/// dropped point stays within the `1e-9` tolerance of `contains` for
/// coordinates up to ~1e3.
const HULL_EPS: f64 = 1e-13;

/// Largest mitre length of [`ConvexPolygon::offset`], as a multiple of the
/// margin (SVG's default): sharper corners are squared off instead.
pub const MITER_LIMIT: f64 = 4.0;

/// Distance tolerance of [`ConvexPolygon::contains`].
const CONTAINS_EPS: f64 = 1e-9;

/// A convex polygon with counter-clockwise vertices (no repeated closing
/// vertex). May be empty (fewer than 3 vertices, zero area) when built from
/// degenerate input; every operation is defined on an empty polygon.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ConvexPolygon {
    vertices: Vec<Point2<f64>>,
}

/// `(a - o) × (b - o)`: positive when `o → a → b` turns left.
#[inline]
fn cross(o: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let u = a - o;
    let v = b - o;
    u.x * v.y - u.y * v.x
}

/// Lexicographic total order on `(x, y)` (inputs are finite).
fn lex(a: &Point2<f64>, b: &Point2<f64>) -> Ordering {
    a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
}

/// Outward unit normal of the CCW edge `a → b`, or `None` for a zero edge.
fn outward_normal(a: &Point2<f64>, b: &Point2<f64>) -> Option<Vector2<f64>> {
    let e = b - a;
    Vector2::new(e.y, -e.x).try_normalize(0.0)
}

/// Distance from `p` to the segment `[a, b]`.
fn segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let e = b - a;
    let len2 = e.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&e) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + e * t)).norm()
}

/// Keeps the part of the convex polygon `poly` (CCW, possibly open list)
/// where `n·p ≤ c` (one Sutherland–Hodgman pass).
fn clip_half_plane(poly: &[Point2<f64>], n: &Vector2<f64>, c: f64) -> Vec<Point2<f64>> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    let Some(last) = poly.last() else {
        return out;
    };
    let mut prev = *last;
    let mut d_prev = n.dot(&prev.coords) - c;
    for cur in poly {
        let d_cur = n.dot(&cur.coords) - c;
        let prev_in = d_prev <= 0.0;
        let cur_in = d_cur <= 0.0;
        if prev_in != cur_in {
            // d_prev and d_cur have opposite signs, so the denominator is
            // non-zero and t ∈ [0, 1].
            let t = d_prev / (d_prev - d_cur);
            out.push(prev + (cur - prev) * t);
        }
        if cur_in {
            out.push(*cur);
        }
        prev = *cur;
        d_prev = d_cur;
    }
    out
}

impl ConvexPolygon {
    /// Convex hull of `points` (CCW). Collinear, repeated or fewer than three
    /// points give an empty polygon. Non-finite points are ignored.
    ///
    /// Andrew's monotone chain (deterministic, `O(n log n)`); the vertex list
    /// starts at the lexicographically smallest `(x, y)` point.
    pub fn hull(points: &[Point2<f64>]) -> Self {
        let mut pts: Vec<Point2<f64>> = points
            .iter()
            .filter(|p| p.x.is_finite() && p.y.is_finite())
            .copied()
            .collect();
        pts.sort_by(lex);
        pts.dedup();
        if pts.len() < 3 {
            return Self::default();
        }
        let (mut lo, mut hi) = (pts[0].coords, pts[0].coords);
        for p in &pts {
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        let extent = (hi - lo).amax();
        if !extent.is_finite() || extent <= 0.0 {
            return Self::default();
        }
        let magnitude = lo.abs().sup(&hi.abs()).max();
        let tol = HULL_EPS * (extent + magnitude);
        // `a` is dropped when it is not strictly left of the chord `o → p`.
        let keep = |o: &Point2<f64>, a: &Point2<f64>, p: &Point2<f64>| {
            cross(o, a, p) > tol * (p - o).norm()
        };

        let mut h: Vec<Point2<f64>> = Vec::with_capacity(pts.len() + 1);
        // Lower chain, left to right.
        for p in &pts {
            while h.len() >= 2 && !keep(&h[h.len() - 2], &h[h.len() - 1], p) {
                h.pop();
            }
            h.push(*p);
        }
        // Upper chain, right to left.
        let lower_len = h.len() + 1;
        for p in pts.iter().rev().skip(1) {
            while h.len() >= lower_len && !keep(&h[h.len() - 2], &h[h.len() - 1], p) {
                h.pop();
            }
            h.push(*p);
        }
        h.pop(); // the first point again
        if h.len() < 3 {
            return Self::default();
        }
        Self { vertices: h }
    }

    /// A polygon from vertices already known to be convex and CCW (e.g. read
    /// from a file); re-hulled if they are not.
    pub fn from_vertices(vertices: Vec<Point2<f64>>) -> Self {
        Self::hull(&vertices)
    }

    /// Axis-aligned rectangle `[min.x, max.x] × [min.y, max.y]` (empty when
    /// degenerate): a convenience for tests and synthetic panes.
    pub fn rectangle(min: Point2<f64>, max: Point2<f64>) -> Self {
        Self::hull(&[
            min,
            Point2::new(max.x, min.y),
            max,
            Point2::new(min.x, max.y),
        ])
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Point2<f64>] {
        &self.vertices
    }

    /// Whether the polygon has no area.
    pub fn is_empty(&self) -> bool {
        self.vertices.len() < 3
    }

    /// The edges `(a, b)` in CCW order, closing edge included.
    fn edges(&self) -> impl Iterator<Item = (&Point2<f64>, &Point2<f64>)> {
        let n = self.vertices.len();
        (0..n).map(move |i| (&self.vertices[i], &self.vertices[(i + 1) % n]))
    }

    /// Area (shoelace); 0 when empty.
    pub fn area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        // Relative to the first vertex, for precision far from the origin.
        let o = self.vertices[0];
        let twice: f64 = self
            .vertices
            .windows(2)
            .map(|w| cross(&o, &w[0], &w[1]))
            .sum();
        0.5 * twice.max(0.0)
    }

    /// Centroid of the area; `None` when empty.
    pub fn centroid(&self) -> Option<Point2<f64>> {
        if self.is_empty() {
            return None;
        }
        let o = self.vertices[0];
        let mut twice_area = 0.0;
        let mut acc = Vector2::zeros();
        for w in self.vertices.windows(2) {
            let c = cross(&o, &w[0], &w[1]);
            twice_area += c;
            acc += ((w[0] - o) + (w[1] - o)) * c;
        }
        if twice_area > 0.0 {
            Some(o + acc / (3.0 * twice_area))
        } else {
            // Unreachable for a hull-built polygon; fall back to the mean.
            let mean = self
                .vertices
                .iter()
                .fold(Vector2::zeros(), |s, p| s + p.coords)
                / self.vertices.len() as f64;
            Some(Point2::from(mean))
        }
    }

    /// Whether `p` is inside or on the boundary (within `1e-9`).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        if self.is_empty() || !(p.x.is_finite() && p.y.is_finite()) {
            return false;
        }
        self.edges().all(|(a, b)| match outward_normal(a, b) {
            Some(n) => n.dot(&(p - a)) <= CONTAINS_EPS,
            None => true,
        })
    }

    /// Signed distance from `p` to the boundary: negative inside, positive
    /// outside (for an empty polygon: +infinity).
    pub fn signed_distance(&self, p: &Point2<f64>) -> f64 {
        if self.is_empty() {
            return f64::INFINITY;
        }
        let max_line = self.max_edge_line(p);
        if max_line <= 0.0 {
            max_line
        } else {
            self.boundary_distance(p)
        }
    }

    /// Whether `p` lies within `margin` of the polygon: `signed_distance(p)
    /// <= margin`, without the distances to the edges where the edge lines
    /// already decide (a point farther than `margin` outside one edge's line
    /// is farther than that from the polygon).
    pub fn within(&self, p: &Point2<f64>, margin: f64) -> bool {
        if self.is_empty() {
            return f64::INFINITY <= margin;
        }
        let max_line = self.max_edge_line(p);
        if max_line <= 0.0 || max_line > margin {
            return max_line <= margin;
        }
        self.boundary_distance(p) <= margin
    }

    /// The largest signed distance from `p` to an edge's line (outward
    /// positive): at most 0 exactly when `p` is inside, and then its
    /// magnitude is the distance to the boundary; outside, a lower bound of
    /// it.
    fn max_edge_line(&self, p: &Point2<f64>) -> f64 {
        self.edges()
            .filter_map(|(a, b)| outward_normal(a, b).map(|n| n.dot(&(p - a))))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The distance from `p` to the nearest edge segment.
    fn boundary_distance(&self, p: &Point2<f64>) -> f64 {
        self.edges()
            .map(|(a, b)| segment_distance(p, a, b))
            .fold(f64::INFINITY, f64::min)
    }

    /// The intersection of two convex polygons (possibly empty).
    ///
    /// Sutherland–Hodgman: `self` clipped by every edge half-plane of
    /// `other`, then re-hulled to drop round-off slivers.
    pub fn intersection(&self, other: &Self) -> Self {
        if self.is_empty() || other.is_empty() {
            return Self::default();
        }
        let mut poly = self.vertices.clone();
        for (a, b) in other.edges() {
            let Some(n) = outward_normal(a, b) else {
                continue;
            };
            poly = clip_half_plane(&poly, &n, n.dot(&a.coords));
            if poly.len() < 3 {
                return Self::default();
            }
        }
        Self::hull(&poly)
    }

    /// The part of the polygon in the half-plane `normal · x <= offset`.
    pub fn clip(&self, normal: &Vector2<f64>, offset: f64) -> Self {
        if self.is_empty() || !offset.is_finite() || !(normal.x.is_finite() && normal.y.is_finite())
        {
            return Self::default();
        }
        let poly = clip_half_plane(&self.vertices, normal, offset);
        if poly.len() < 3 {
            return Self::default();
        }
        Self::hull(&poly)
    }

    /// Area of the intersection.
    pub fn intersection_area(&self, other: &Self) -> f64 {
        self.intersection(other).area()
    }

    /// Convex hull of the union of both vertex sets.
    pub fn union_hull(&self, other: &Self) -> Self {
        let mut pts = Vec::with_capacity(self.vertices.len() + other.vertices.len());
        pts.extend_from_slice(&self.vertices);
        pts.extend_from_slice(&other.vertices);
        Self::hull(&pts)
    }

    /// The polygon grown (positive) or shrunk (negative) by `margin` along
    /// every edge normal; shrinking past the centre gives an empty polygon.
    ///
    /// Growing intersects adjacent offset edge lines (a mitred offset); at a
    /// sharp vertex whose mitre would exceed [`MITER_LIMIT`]` · margin` the
    /// corner is squared off at distance `margin` from the vertex instead, so
    /// thin slivers do not grow long spikes. Either way the result contains
    /// every point within `margin` of the original polygon. Shrinking clips
    /// the polygon by every inward-shifted edge half-plane. A non-finite
    /// margin gives an empty polygon.
    pub fn offset(&self, margin: f64) -> Self {
        if self.is_empty() || !margin.is_finite() {
            return Self::default();
        }
        if margin == 0.0 {
            return self.clone();
        }
        let normals: Vec<Option<Vector2<f64>>> =
            self.edges().map(|(a, b)| outward_normal(a, b)).collect();
        if margin < 0.0 {
            let mut poly = self.vertices.clone();
            for ((a, _), n) in self.edges().zip(&normals) {
                let Some(n) = n else { continue };
                poly = clip_half_plane(&poly, n, n.dot(&a.coords) + margin);
                if poly.len() < 3 {
                    return Self::default();
                }
            }
            return Self::hull(&poly);
        }
        let k = self.vertices.len();
        let mut pts = Vec::with_capacity(2 * k);
        for (i, v) in self.vertices.iter().enumerate() {
            // Edge i-1 ends at v, edge i starts at it.
            let (Some(n1), Some(n2)) = (normals[(i + k - 1) % k], normals[i]) else {
                continue;
            };
            // cos γ, γ the half-angle between the normals; the mitre point
            // is v + margin · b / cos γ with b the unit bisector.
            let cos_g = (0.5 * (1.0 + n1.dot(&n2))).max(0.0).sqrt();
            if cos_g * MITER_LIMIT >= 1.0 {
                pts.push(v + (n1 + n2) * (margin / (2.0 * cos_g * cos_g)));
            } else {
                // Square cap at distance `margin` along the bisector: the
                // points where it meets the two offset lines.
                let b = (n1 + n2)
                    .try_normalize(1e-12)
                    .unwrap_or_else(|| Vector2::new(-n1.y, n1.x));
                let side = Vector2::new(-b.y, b.x);
                let sin_g = (1.0 - cos_g * cos_g).max(0.0).sqrt();
                let half = margin * (1.0 - cos_g) / sin_g.max(f64::MIN_POSITIVE);
                let half = half.min(margin);
                pts.push(v + b * margin + side * half);
                pts.push(v + b * margin - side * half);
            }
        }
        Self::hull(&pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn degenerate_inputs_are_empty() {
        assert!(ConvexPolygon::hull(&[]).is_empty());
        assert!(ConvexPolygon::hull(&[p(0.0, 0.0), p(1.0, 1.0)]).is_empty());
        assert!(ConvexPolygon::hull(&[p(0.0, 0.0), p(1.0, 1.0), p(2.0, 2.0)]).is_empty());
        assert!(ConvexPolygon::hull(&[p(1.0, 1.0); 5]).is_empty());
        assert!(ConvexPolygon::hull(&[p(0.0, 0.0), p(f64::NAN, 1.0), p(1.0, 0.0)]).is_empty());
        let e = ConvexPolygon::default();
        assert_eq!(e.area(), 0.0);
        assert_eq!(e.centroid(), None);
        assert!(!e.contains(&p(0.0, 0.0)));
        assert_eq!(e.signed_distance(&p(0.0, 0.0)), f64::INFINITY);
        assert!(e.intersection(&e).is_empty());
        assert!(e.union_hull(&e).is_empty());
        assert!(e.offset(1.0).is_empty());
    }

    #[test]
    fn square_basics() {
        let sq = ConvexPolygon::hull(&[
            p(1.0, 1.0),
            p(0.0, 0.0),
            p(0.5, 0.0),
            p(1.0, 0.0),
            p(0.0, 1.0),
            p(0.5, 0.5),
            p(f64::INFINITY, 0.0),
        ]);
        assert_eq!(
            sq.vertices(),
            &[p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]
        );
        assert_eq!(sq.area(), 1.0);
        assert_eq!(sq.centroid(), Some(p(0.5, 0.5)));
        assert!(sq.contains(&p(1.0, 0.5)));
        assert!(!sq.contains(&p(1.0 + 1e-6, 0.5)));
        assert!((sq.signed_distance(&p(0.25, 0.5)) + 0.25).abs() < 1e-15);
        assert!((sq.signed_distance(&p(2.0, 2.0)) - 2f64.sqrt()).abs() < 1e-15);
        let grown = sq.offset(0.5);
        assert!((grown.area() - 4.0).abs() < 1e-12);
        let shrunk = sq.offset(-0.25);
        assert!((shrunk.area() - 0.25).abs() < 1e-12);
        assert!(sq.offset(-0.5).is_empty());
        assert!(sq.offset(-3.0).is_empty());
    }

    #[test]
    fn needle_offset_does_not_blow_up() {
        let needle = ConvexPolygon::hull(&[p(0.0, 0.0), p(1e6, 0.0), p(1e6, 1e-3)]);
        assert!(!needle.is_empty());
        let g = needle.offset(1.0);
        // Square caps: nothing further than √2 · margin from the needle.
        for v in g.vertices() {
            assert!(needle.signed_distance(v) <= 2f64.sqrt() + 1e-9);
        }
        for v in needle.vertices() {
            assert!(g.signed_distance(v) <= -1.0 + 1e-9);
        }
    }

    proptest::proptest! {
        /// `within` is `signed_distance <= margin`, its shortcut included.
        #[test]
        fn within_is_the_signed_distance_against_the_margin(
            pts in proptest::collection::vec((-5.0f64..5.0, -5.0f64..5.0), 3..12),
            q in (-8.0f64..8.0, -8.0f64..8.0),
            margin in -1.0f64..3.0,
        ) {
            let hull = ConvexPolygon::hull(&pts.iter().map(|&(x, y)| p(x, y)).collect::<Vec<_>>());
            let q = p(q.0, q.1);
            proptest::prop_assert_eq!(hull.within(&q, margin), hull.signed_distance(&q) <= margin);
        }
    }
}
