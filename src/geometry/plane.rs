//! Planes in Hessian normal form.

use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// A plane `n·x + d = 0` with unit normal `n`.
///
/// Signed distance `s(x) = n·x + d` is positive in front of the plane (the
/// side its observers are on) and negative behind it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vector3<f64>,
    /// Offset: the signed distance of the coordinate origin.
    pub d: f64,
}

impl Plane {
    /// A plane from a (not necessarily unit) normal and offset, scaled so the
    /// normal is unit. `None` when the normal is (near) zero or not finite.
    pub fn new(normal: Vector3<f64>, d: f64) -> Option<Self> {
        let norm = normal.norm();
        if !(norm > 1e-12) || !norm.is_finite() || !d.is_finite() {
            return None;
        }
        Some(Self {
            normal: normal / norm,
            d: d / norm,
        })
    }

    /// The plane through `point` with the given normal direction.
    pub fn from_point_normal(point: &Point3<f64>, normal: &Vector3<f64>) -> Option<Self> {
        let n = normal.try_normalize(1e-12)?;
        Some(Self {
            normal: n,
            d: -n.dot(&point.coords),
        })
    }

    /// Coefficients `(a, b, c, d)`.
    pub fn coefficients(&self) -> [f64; 4] {
        [self.normal.x, self.normal.y, self.normal.z, self.d]
    }

    /// Signed distance `n·p + d`.
    #[inline]
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        self.normal.dot(&p.coords) + self.d
    }

    /// Orthogonal projection of `p` onto the plane.
    #[inline]
    pub fn project(&self, p: &Point3<f64>) -> Point3<f64> {
        p - self.normal * self.signed_distance(p)
    }

    /// Householder mirror `p - 2 s(p) n`: where a reflection really is.
    #[inline]
    pub fn mirror(&self, p: &Point3<f64>) -> Point3<f64> {
        p - self.normal * (2.0 * self.signed_distance(p))
    }

    /// Mirror of a direction (no offset): `v - 2 (n·v) n`.
    #[inline]
    pub fn mirror_vector(&self, v: &Vector3<f64>) -> Vector3<f64> {
        v - self.normal * (2.0 * self.normal.dot(v))
    }

    /// The same plane expressed in frame B, given `t` mapping frame A to B:
    /// `n_B = R n_A`, `d_B = d_A - n_B·t`.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        let n = t.rotation * self.normal;
        Self {
            normal: n,
            d: self.d - n.dot(&t.translation.vector),
        }
    }

    /// The same plane with the opposite orientation.
    pub fn flipped(&self) -> Self {
        Self {
            normal: -self.normal,
            d: -self.d,
        }
    }

    /// This plane oriented so that `viewpoint` is on its positive side.
    pub fn facing(&self, viewpoint: &Point3<f64>) -> Self {
        if self.signed_distance(viewpoint) < 0.0 {
            self.flipped()
        } else {
            *self
        }
    }

    /// Parameter `t > 0` at which the ray `origin + t·dir` meets the plane,
    /// or `None` when the ray is parallel (|n·dir| < 1e-9 |dir|) or points
    /// away. With a unit `dir`, `t` is the range along the beam.
    #[inline]
    pub fn ray_intersection(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<f64> {
        let denom = self.normal.dot(dir);
        if denom.abs() < 1e-9 * dir.norm() {
            return None;
        }
        let t = -self.signed_distance(origin) / denom;
        (t > 0.0).then_some(t)
    }

    /// Cosine of the angle between the normals (orientation-aware).
    pub fn normal_cosine(&self, other: &Self) -> f64 {
        self.normal.dot(&other.normal)
    }
}
