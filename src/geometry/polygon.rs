//! Convex polygons in a plane chart: reflective-plane boundaries.

use nalgebra::Point2;

/// A convex polygon with counter-clockwise vertices (no repeated closing
/// vertex). May be empty (fewer than 3 vertices, zero area) when built from
/// degenerate input; every operation is defined on an empty polygon.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ConvexPolygon {
    vertices: Vec<Point2<f64>>,
}

impl ConvexPolygon {
    /// Convex hull of `points` (CCW). Collinear, repeated or fewer than three
    /// points give an empty polygon. Non-finite points are ignored.
    pub fn hull(points: &[Point2<f64>]) -> Self {
        todo!("hull via parry2d-f64: {}", points.len())
    }

    /// A polygon from vertices already known to be convex and CCW (e.g. read
    /// from a file); re-hulled if they are not.
    pub fn from_vertices(vertices: Vec<Point2<f64>>) -> Self {
        Self::hull(&vertices)
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Point2<f64>] {
        &self.vertices
    }

    /// Whether the polygon has no area.
    pub fn is_empty(&self) -> bool {
        self.vertices.len() < 3
    }

    /// Area (shoelace); 0 when empty.
    pub fn area(&self) -> f64 {
        todo!()
    }

    /// Centroid of the area; `None` when empty.
    pub fn centroid(&self) -> Option<Point2<f64>> {
        todo!()
    }

    /// Whether `p` is inside or on the boundary (within `1e-9`).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        todo!("{p}")
    }

    /// Signed distance from `p` to the boundary: negative inside, positive
    /// outside (for an empty polygon: +infinity).
    pub fn signed_distance(&self, p: &Point2<f64>) -> f64 {
        todo!("{p}")
    }

    /// The intersection of two convex polygons (possibly empty).
    pub fn intersection(&self, other: &Self) -> Self {
        todo!("{}", other.vertices.len())
    }

    /// Area of the intersection.
    pub fn intersection_area(&self, other: &Self) -> f64 {
        self.intersection(other).area()
    }

    /// Convex hull of the union of both vertex sets.
    pub fn union_hull(&self, other: &Self) -> Self {
        todo!("{}", other.vertices.len())
    }

    /// The polygon grown (positive) or shrunk (negative) by `margin` along
    /// every edge normal; shrinking past the centre gives an empty polygon.
    pub fn offset(&self, margin: f64) -> Self {
        todo!("{margin}")
    }
}
