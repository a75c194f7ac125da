//! Our plane landmark (GTSAM `OrientedPlane3`: unit normal on S² with the
//! `Unit3` basis, plus offset) as a factrs [`Variable`], and the sphere
//! operations written once for any factrs [`Numeric`] (f64 or the dual
//! numbers factrs differentiates with).
//!
//! factrs models every variable as a Lie group and updates it with
//! `x ⊕ ξ = x · exp(ξ)` (its default right convention), also when it seeds
//! dual numbers for forward-mode Jacobians. S² × ℝ is not a group, so
//! [`FactrsPlane`] carries a flag: `exp(ξ)` builds a *tangent* element and
//! composing a plane with a tangent element is our retraction
//! `(Exp_n(B ξ₀₁), d + ξ₂)`. That is the only composition factrs' Gauss–Newton
//! and Levenberg–Marquardt use; the group axioms beyond it (plane·plane,
//! inverse of a plane) are not meaningful and documented as such.

use std::fmt;

use factrs::dtype;
use factrs::linalg::{Const, Numeric, SupersetOf, Vector3, VectorViewX, VectorX};
use factrs::variables::Variable;

/// `T::from(v)` without naming the (ambiguous) `From` impl at call sites.
#[inline]
pub(crate) fn c<T: Numeric>(v: f64) -> T {
    T::from(v)
}

/// GTSAM's `Unit3` tangent basis `(b1, b2)` at the unit vector `p`: `a` is
/// the axis of smallest `|p_i|` (first on ties), `b1 = normalize(p × a)`,
/// `b2 = p × b1` (same rule as `backend::unit3::basis`).
pub(crate) fn basis<T: Numeric>(p: &Vector3<T>) -> (Vector3<T>, Vector3<T>) {
    let (mx, my, mz) = (p.x * p.x, p.y * p.y, p.z * p.z);
    let a = if mx <= my && mx <= mz {
        Vector3::new(c::<T>(1.0), c::<T>(0.0), c::<T>(0.0))
    } else if my <= mx && my <= mz {
        Vector3::new(c::<T>(0.0), c::<T>(1.0), c::<T>(0.0))
    } else {
        Vector3::new(c::<T>(0.0), c::<T>(0.0), c::<T>(1.0))
    };
    let b1 = p.cross(&a).normalize();
    let b2 = p.cross(&b1);
    (b1, b2)
}

/// Sphere exponential `Exp_p(B v)` (GTSAM `Unit3::retract`), renormalised.
/// Below `θ = ε` it is `normalize(p + B v)`, which has the right derivative
/// at `v = 0` (where `√θ²` would not be differentiable).
pub(crate) fn retract<T: Numeric>(p: &Vector3<T>, v0: T, v1: T) -> Vector3<T> {
    let (b1, b2) = basis(p);
    let xi = b1 * v0 + b2 * v1;
    let theta2 = xi.norm_squared();
    if theta2 < c::<T>(f64::EPSILON * f64::EPSILON) {
        return (p + xi).normalize();
    }
    let theta = theta2.sqrt();
    (p * theta.cos() + xi * (theta.sin() / theta)).normalize()
}

/// `θ / sin θ` from `x = cos θ`, with the Taylor series near `x = 1`
/// (`backend::unit3` uses the same split).
fn theta_over_sin<T: Numeric>(x: T) -> T {
    if x > c::<T>(1.0 - 1e-5) {
        let e = x - c::<T>(1.0);
        c::<T>(1.0) - e / c::<T>(3.0) + e * e * c::<T>(2.0 / 15.0)
    } else {
        x.acos() / (c::<T>(1.0) - x * x).sqrt()
    }
}

/// GTSAM `Unit3::localCoordinates(p, q) = Bᵀ(p) (θ / sin θ)(q − (p·q) p)`;
/// `(π, 0)` when `p` and `q` are antipodal, as GTSAM and our back-end.
pub(crate) fn local_coordinates<T: Numeric>(p: &Vector3<T>, q: &Vector3<T>) -> (T, T) {
    let mut x = p.dot(q);
    if x < c::<T>(-1.0 + 1e-12) {
        return (c::<T>(std::f64::consts::PI), c::<T>(0.0));
    }
    if x > c::<T>(1.0) {
        x = c::<T>(1.0);
    }
    let w = (q - p * x) * theta_over_sin(x);
    let (b1, b2) = basis(p);
    (b1.dot(&w), b2.dot(&w))
}

/// A plane landmark `n·x + d = 0` for factrs, or (with `tangent`) an
/// update `ξ = (v₀, v₁, δd)` stored in `(normal.x, normal.y, d)`.
#[derive(Clone)]
pub struct FactrsPlane<T: Numeric = dtype> {
    /// Unit normal (a plane) or `(v₀, v₁, 0)` (a tangent element).
    pub normal: Vector3<T>,
    /// Offset (a plane) or `δd` (a tangent element).
    pub d: T,
    /// Whether this is a tangent element made by `exp`.
    pub tangent: bool,
}

impl<T: Numeric> FactrsPlane<T> {
    /// A plane from a unit normal and offset.
    pub fn new(normal: Vector3<T>, d: T) -> Self {
        Self {
            normal,
            d,
            tangent: false,
        }
    }

    /// Our retraction `(Exp_n(B v), d + δd)` by the tangent element `t`.
    fn retract_by(&self, t: &Self) -> Self {
        Self::new(retract(&self.normal, t.normal.x, t.normal.y), self.d + t.d)
    }
}

#[factrs::mark]
impl<T: Numeric> Variable for FactrsPlane<T> {
    type T = T;
    type Dim = Const<3>;
    type Alias<TT: Numeric> = FactrsPlane<TT>;

    /// The zero update.
    fn identity() -> Self {
        Self {
            normal: Vector3::zeros(),
            d: c::<T>(0.0),
            tangent: true,
        }
    }

    /// The negated update; a plane is returned unchanged (not meaningful).
    fn inverse(&self) -> Self {
        if self.tangent {
            Self {
                normal: -self.normal,
                d: -self.d,
                tangent: true,
            }
        } else {
            self.clone()
        }
    }

    /// plane · update = retraction (right), update · plane = retraction
    /// (left convention), update · update = sum; plane · plane is not
    /// meaningful and returns `self`.
    fn compose(&self, other: &Self) -> Self {
        match (self.tangent, other.tangent) {
            (false, true) => self.retract_by(other),
            (true, false) => other.retract_by(self),
            (true, true) => Self {
                normal: self.normal + other.normal,
                d: self.d + other.d,
                tangent: true,
            },
            (false, false) => self.clone(),
        }
    }

    /// The tangent element of `ξ`.
    fn exp(delta: VectorViewX<T>) -> Self {
        Self {
            normal: Vector3::new(delta[0], delta[1], c::<T>(0.0)),
            d: delta[2],
            tangent: true,
        }
    }

    /// A tangent element's `ξ`; for a plane, its local coordinates in the
    /// chart at `+z` with zero offset (only for display: the optimisers
    /// never take the logarithm of a plane).
    fn log(&self) -> VectorX<T> {
        if self.tangent {
            VectorX::from_vec(vec![self.normal.x, self.normal.y, self.d])
        } else {
            let z = Vector3::new(c::<T>(0.0), c::<T>(0.0), c::<T>(1.0));
            let (v0, v1) = local_coordinates(&z, &self.normal);
            VectorX::from_vec(vec![v0, v1, self.d])
        }
    }

    fn cast<TT: Numeric + SupersetOf<Self::T>>(&self) -> Self::Alias<TT> {
        FactrsPlane {
            normal: self.normal.cast(),
            d: TT::from_subset(&self.d),
            tangent: self.tangent,
        }
    }
}

impl<T: Numeric> fmt::Display for FactrsPlane<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = if self.tangent { "PlaneDelta" } else { "Plane" };
        write!(
            f,
            "{kind}(n: [{}, {}, {}], d: {})",
            self.normal.x, self.normal.y, self.normal.z, self.d
        )
    }
}

impl<T: Numeric> fmt::Debug for FactrsPlane<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}
