//! Variables of the pose-plane graph: keys, plane landmarks on S² × ℝ and
//! the [`Values`] container with its manifold updates.
//!
//! Poses are `T_world_sensor` updated on the right, `X · exp(δ)` with
//! `δ = (ρ, φ)` (6-D, [`se3::retract`]). A plane landmark is GTSAM's
//! `OrientedPlane3`: a unit normal updated on the sphere with the `Unit3`
//! basis (2-D) and an offset `d` updated additively (1-D).

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use nalgebra::{Isometry3, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use super::unit3;
use crate::geometry::se3;
use crate::geometry::Plane;
use crate::{Error, Result};

/// A variable's identity, printed GTSAM-symbol style: `x7` for pose 7,
/// `p3` for plane landmark 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Key {
    /// A pose `T_world_sensor` (6 degrees of freedom).
    Pose(u32),
    /// A plane landmark in the world frame (3 degrees of freedom).
    Plane(u32),
}

impl Key {
    /// Dimension of the variable's tangent space.
    pub fn dim(self) -> usize {
        match self {
            Key::Pose(_) => 6,
            Key::Plane(_) => 3,
        }
    }
}

impl fmt::Display for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Key::Pose(i) => write!(f, "x{i}"),
            Key::Plane(i) => write!(f, "p{i}"),
        }
    }
}

impl FromStr for Key {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("bad key '{s}' (expected x<id> for a pose or p<id> for a plane)");
        let (kind, id) = s.split_at(s.char_indices().nth(1).map_or(s.len(), |(i, _)| i));
        let id: u32 = id.parse().map_err(|_| bad())?;
        match kind {
            "x" => Ok(Key::Pose(id)),
            "p" => Ok(Key::Plane(id)),
            _ => Err(bad()),
        }
    }
}

impl TryFrom<String> for Key {
    type Error = String;
    fn try_from(s: String) -> std::result::Result<Self, String> {
        s.parse()
    }
}

impl From<Key> for String {
    fn from(k: Key) -> String {
        k.to_string()
    }
}

/// A plane landmark `n·x + d = 0` (world frame) as a manifold variable:
/// unit normal on S² plus offset, 3 degrees of freedom (GTSAM
/// `OrientedPlane3`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneVar {
    /// Unit normal.
    pub normal: Vector3<f64>,
    /// Offset `d`.
    pub d: f64,
}

impl PlaneVar {
    /// A landmark from a (not necessarily unit) normal and offset; `None`
    /// when the normal is (near) zero or anything is not finite.
    pub fn new(normal: Vector3<f64>, d: f64) -> Option<Self> {
        Plane::new(normal, d).map(Self::from)
    }

    /// Update `(Exp_n(B v₀₁), d + v₂)` (GTSAM `OrientedPlane3::retract`).
    pub fn retract(&self, v: &Vector3<f64>) -> Self {
        Self {
            normal: unit3::retract(&self.normal, &Vector2::new(v.x, v.y)),
            d: self.d + v.z,
        }
    }

    /// Inverse of [`PlaneVar::retract`]: `(n.localCoordinates(o.n), o.d − d)`.
    pub fn local(&self, other: &Self) -> Vector3<f64> {
        let v = unit3::local_coordinates(&self.normal, &other.normal);
        Vector3::new(v.x, v.y, other.d - self.d)
    }

    /// The landmark as a plain [`Plane`].
    pub fn plane(&self) -> Plane {
        Plane {
            normal: self.normal,
            d: self.d,
        }
    }
}

impl From<Plane> for PlaneVar {
    fn from(p: Plane) -> Self {
        Self {
            normal: p.normal,
            d: p.d,
        }
    }
}

/// Current estimates of all variables, keyed by id. Ordered maps keep every
/// iteration order (and therefore every result) deterministic.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Values {
    /// Poses `T_world_sensor` by pose id.
    pub poses: BTreeMap<u32, Isometry3<f64>>,
    /// Plane landmarks (world frame) by plane id.
    pub planes: BTreeMap<u32, PlaneVar>,
}

impl Values {
    /// The pose with this id, or an error naming the missing key.
    #[inline]
    pub fn pose(&self, id: u32) -> Result<&Isometry3<f64>> {
        self.poses
            .get(&id)
            .ok_or_else(|| Error::Input(format!("no value for variable {}", Key::Pose(id))))
    }

    /// The plane landmark with this id, or an error naming the missing key.
    #[inline]
    pub fn plane(&self, id: u32) -> Result<&PlaneVar> {
        self.planes
            .get(&id)
            .ok_or_else(|| Error::Input(format!("no value for variable {}", Key::Plane(id))))
    }

    /// Whether a value exists for `key`.
    pub fn contains(&self, key: Key) -> bool {
        match key {
            Key::Pose(i) => self.poses.contains_key(&i),
            Key::Plane(i) => self.planes.contains_key(&i),
        }
    }

    /// All keys, poses first, each group by id.
    pub fn keys(&self) -> impl Iterator<Item = Key> + '_ {
        self.poses
            .keys()
            .map(|&i| Key::Pose(i))
            .chain(self.planes.keys().map(|&i| Key::Plane(i)))
    }

    /// Apply the tangent update `delta` (length `key.dim()`) to one variable.
    pub fn retract_key(&mut self, key: Key, delta: &[f64]) -> Result<()> {
        if delta.len() != key.dim() {
            return Err(Error::Input(format!(
                "update of {key} has {} entries, expected {}",
                delta.len(),
                key.dim()
            )));
        }
        match key {
            Key::Pose(i) => {
                let x = self
                    .poses
                    .get_mut(&i)
                    .ok_or_else(|| Error::Input(format!("no value for variable {key}")))?;
                *x = se3::retract(x, &Vector6::from_column_slice(delta));
            }
            Key::Plane(i) => {
                let p = self
                    .planes
                    .get_mut(&i)
                    .ok_or_else(|| Error::Input(format!("no value for variable {key}")))?;
                *p = p.retract(&Vector3::from_column_slice(delta));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_round_trips_through_text() {
        for k in [Key::Pose(0), Key::Plane(17), Key::Pose(u32::MAX)] {
            assert_eq!(k.to_string().parse::<Key>().unwrap(), k);
        }
        assert!("y3".parse::<Key>().is_err());
        assert!("x".parse::<Key>().is_err());
        assert!("x-1".parse::<Key>().is_err());
        assert!("".parse::<Key>().is_err());
    }
}
