//! Planar polygon surfaces: the only primitive of a scene.
//!
//! Rooms, boxes, walls and floors are all expanded into [`Surface`]s; the
//! ray caster triangulates them and the ground-truth plane export reads their
//! plane and boundary.

use glam::DVec3;

/// Largest distance of a vertex from the plane of its polygon, metres.
const PLANARITY_TOLERANCE: f64 = 1e-3;
/// Smallest polygon area accepted, m².
const MIN_AREA: f64 = 1e-6;
/// Largest coordinate accepted, metres (keeps every product finite).
pub const MAX_COORDINATE: f64 = 1e6;
/// Most vertices of one polygon (ear clipping is quadratic or worse).
pub const MAX_VERTICES: usize = 1000;

/// A planar polygon with a material.
///
/// The vertices go counter-clockwise seen from the side `normal` points to;
/// the plane is `normal·x + d = 0`. Surfaces are two-sided for the ray
/// caster: a beam can hit them from either side.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Boundary vertices, world frame (counter-clockwise around `normal`).
    pub vertices: Vec<DVec3>,
    /// Unit normal (from the vertex order, Newell's method).
    pub normal: DVec3,
    /// Offset of the plane `normal·x + d = 0`.
    pub d: f64,
    /// Index into the scene's materials.
    pub material: usize,
    /// Where the surface came from in the scene file (e.g. `walls[2]`), for
    /// messages.
    pub origin: String,
}

impl Surface {
    /// A surface from its boundary. Fails (with a message) when there are
    /// fewer than three or more than [`MAX_VERTICES`] vertices, the polygon
    /// is degenerate (no area), a coordinate is not finite, or a vertex is
    /// more than 1 mm off the plane.
    pub fn new(vertices: Vec<DVec3>, material: usize, origin: String) -> Result<Self, String> {
        if vertices.len() < 3 {
            return Err(format!(
                "a polygon needs at least 3 vertices, got {}",
                vertices.len()
            ));
        }
        if vertices.len() > MAX_VERTICES {
            return Err(format!(
                "a polygon may have at most {MAX_VERTICES} vertices, got {}",
                vertices.len()
            ));
        }
        if vertices
            .iter()
            .any(|v| !v.is_finite() || v.abs().max_element() > MAX_COORDINATE)
        {
            return Err(format!(
                "vertex coordinates must be finite and within ±{MAX_COORDINATE} m"
            ));
        }
        // Newell's method: robust normal of a (possibly non-convex) polygon,
        // its length is twice the area.
        let mut n = DVec3::ZERO;
        for (i, a) in vertices.iter().enumerate() {
            let b = vertices[(i + 1) % vertices.len()];
            n += a.cross(b);
        }
        let area = 0.5 * n.length();
        if !(area > MIN_AREA) {
            return Err(format!(
                "polygon is degenerate (area {area:.2e} m²): vertices are collinear or repeated"
            ));
        }
        let normal = n / (2.0 * area);
        let centroid = vertices.iter().copied().sum::<DVec3>() / vertices.len() as f64;
        let d = -normal.dot(centroid);
        let off = vertices
            .iter()
            .map(|v| (normal.dot(*v) + d).abs())
            .fold(0.0, f64::max);
        if off > PLANARITY_TOLERANCE {
            return Err(format!(
                "polygon is not planar: a vertex is {off:.4} m off its plane (tolerance {PLANARITY_TOLERANCE} m)"
            ));
        }
        Ok(Self {
            vertices,
            normal,
            d,
            material,
            origin,
        })
    }

    /// Polygon area, m².
    pub fn area(&self) -> f64 {
        let mut n = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            n += a.cross(self.vertices[(i + 1) % self.vertices.len()]);
        }
        0.5 * n.length()
    }

    /// Centroid of the vertices.
    pub fn center(&self) -> DVec3 {
        self.vertices.iter().copied().sum::<DVec3>() / self.vertices.len() as f64
    }

    /// Two in-plane unit axes `(u, v)` with `u × v = normal`.
    pub fn axes(&self) -> (DVec3, DVec3) {
        let n = self.normal;
        let helper = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
        let u = helper.cross(n).normalize();
        let v = n.cross(u);
        (u, v)
    }

    /// Triangulation of the polygon by ear clipping (works for non-convex
    /// simple polygons). Fails when the polygon is self-intersecting.
    pub fn triangles(&self) -> Result<Vec<[DVec3; 3]>, String> {
        let (u, v) = self.axes();
        let pts: Vec<[f64; 2]> = self.vertices.iter().map(|p| [p.dot(u), p.dot(v)]).collect();
        let idx = ear_clip(&pts)
            .ok_or_else(|| "polygon is self-intersecting (cannot triangulate)".to_string())?;
        Ok(idx
            .into_iter()
            .map(|[a, b, c]| [self.vertices[a], self.vertices[b], self.vertices[c]])
            .collect())
    }
}

/// Twice the signed area of triangle `abc` (positive when counter-clockwise).
fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Ear clipping of a simple counter-clockwise polygon; `None` when no ear
/// can be found (self-intersecting input).
fn ear_clip(pts: &[[f64; 2]]) -> Option<Vec<[usize; 3]>> {
    let mut ring: Vec<usize> = (0..pts.len()).collect();
    let scale = pts
        .iter()
        .flat_map(|p| [p[0].abs(), p[1].abs()])
        .fold(1.0, f64::max);
    let eps = 1e-12 * scale * scale;
    let mut out = Vec::with_capacity(pts.len().saturating_sub(2));
    while ring.len() > 3 {
        let n = ring.len();
        let mut clipped = false;
        for i in 0..n {
            let (ia, ib, ic) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let (a, b, c) = (pts[ia], pts[ib], pts[ic]);
            let area = cross2(a, b, c);
            if area.abs() <= eps {
                // Collinear vertex: drop it without emitting a triangle.
                ring.remove(i);
                clipped = true;
                break;
            }
            if area < 0.0 {
                continue; // reflex vertex
            }
            let blocked = ring.iter().any(|&j| {
                j != ia
                    && j != ib
                    && j != ic
                    && cross2(a, b, pts[j]) >= -eps
                    && cross2(b, c, pts[j]) >= -eps
                    && cross2(c, a, pts[j]) >= -eps
            });
            if !blocked {
                out.push([ia, ib, ic]);
                ring.remove(i);
                clipped = true;
                break;
            }
        }
        if !clipped {
            return None;
        }
    }
    if ring.len() == 3 {
        let (a, b, c) = (pts[ring[0]], pts[ring[1]], pts[ring[2]]);
        let area = cross2(a, b, c);
        if area < -eps {
            return None;
        }
        if area > eps {
            out.push([ring[0], ring[1], ring[2]]);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_of(tris: &[[DVec3; 3]]) -> f64 {
        tris.iter()
            .map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length())
            .sum()
    }

    #[test]
    fn rectangle_normal_follows_vertex_order() {
        let s = Surface::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 3.0),
                DVec3::new(0.0, 0.0, 3.0),
            ],
            0,
            "t".into(),
        )
        .unwrap();
        assert!((s.normal - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12);
        assert!((s.area() - 6.0).abs() < 1e-12);
        assert!((area_of(&s.triangles().unwrap()) - 6.0).abs() < 1e-12);
    }

    #[test]
    fn non_convex_polygon_is_triangulated_exactly() {
        // An L shape of area 3.
        let l = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ];
        let s = Surface::new(
            l.iter().map(|&(x, y)| DVec3::new(x, y, 1.0)).collect(),
            0,
            "l".into(),
        )
        .unwrap();
        let tris = s.triangles().unwrap();
        assert_eq!(tris.len(), 4);
        assert!((area_of(&tris) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn bad_polygons_are_rejected_with_a_reason() {
        let collinear = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(Surface::new(collinear, 0, "c".into())
            .unwrap_err()
            .contains("degenerate"));
        let warped = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.1), DVec3::Y];
        assert!(Surface::new(warped, 0, "w".into())
            .unwrap_err()
            .contains("not planar"));
        let bowtie = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        // A bow tie has zero Newell area or cannot be clipped.
        let r = Surface::new(bowtie, 0, "b".into()).and_then(|s| s.triangles().map(|_| ()));
        assert!(r.is_err());
    }
}
