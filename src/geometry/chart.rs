//! A 2-D coordinate chart on a plane.
//!
//! Boundaries (hulls, panes) are convex polygons in a chart; a chart maps
//! 3-D points on (or near) the plane to 2-D coordinates and back.

use nalgebra::{Isometry3, Point2, Point3, Vector3};

use super::Plane;

/// Orthonormal 2-D coordinates `(u, v)` on a plane, with `u × v = n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneChart {
    /// The plane point at chart coordinates (0, 0): the foot of the origin.
    pub origin: Point3<f64>,
    /// First axis, unit, in the plane.
    pub u: Vector3<f64>,
    /// Second axis, unit, in the plane.
    pub v: Vector3<f64>,
    /// Plane normal (`u × v`).
    pub normal: Vector3<f64>,
}

impl PlaneChart {
    /// The canonical chart of `plane`: origin at the foot of the coordinate
    /// origin; `u` horizontal (`z × n`) unless the plane is horizontal, then
    /// `x`-aligned. Deterministic for a given plane.
    pub fn of(plane: &Plane) -> Self {
        let n = plane.normal;
        let u = Vector3::z()
            .cross(&n)
            .try_normalize(1e-6)
            .unwrap_or_else(|| n.cross(&Vector3::x()).cross(&n).normalize());
        let v = n.cross(&u);
        Self {
            origin: Point3::from(-n * plane.d),
            u,
            v,
            normal: n,
        }
    }

    /// Chart coordinates of `p` (the normal component is dropped).
    #[inline]
    pub fn to_2d(&self, p: &Point3<f64>) -> Point2<f64> {
        let r = p - self.origin;
        Point2::new(r.dot(&self.u), r.dot(&self.v))
    }

    /// The plane point at chart coordinates `q`.
    #[inline]
    pub fn to_3d(&self, q: &Point2<f64>) -> Point3<f64> {
        self.origin + self.u * q.x + self.v * q.y
    }

    /// The same chart expressed in another frame (`t` maps the current frame
    /// to the new one). Chart coordinates of a physical point are unchanged,
    /// so polygons in this chart stay valid.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        Self {
            origin: t * self.origin,
            u: t.rotation * self.u,
            v: t.rotation * self.v,
            normal: t.rotation * self.normal,
        }
    }

    /// The plane this chart lies on.
    pub fn plane(&self) -> Plane {
        Plane {
            normal: self.normal,
            d: -self.normal.dot(&self.origin.coords),
        }
    }
}
