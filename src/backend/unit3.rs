//! The unit sphere S² as GTSAM's `Unit3`: a 2-D tangent basis, the sphere
//! exponential retraction and its inverse (`localCoordinates`).
//!
//! Reproducing GTSAM's exact choices (basis rule, retraction, `θ / sin θ`
//! scaling) makes plane residuals, and therefore costs, identical to GTSAM's
//! `OrientedPlane3Factor`, so the two solvers can be compared number for
//! number.

use nalgebra::{Matrix2x3, Matrix3, Matrix3x2, Vector2, Vector3};

use crate::geometry::se3::hat;

/// Tangent basis `B = [b1 b2]` at the unit vector `p` (GTSAM `Unit3::basis`):
/// `a` is the coordinate axis of smallest `|p_i|` (first one on ties),
/// `b1 = normalize(p × a)`, `b2 = p × b1`.
pub fn basis(p: &Vector3<f64>) -> Matrix3x2<f64> {
    let (b1, _, _) = basis_first(p);
    let b2 = p.cross(&b1);
    Matrix3x2::from_columns(&[b1, b2])
}

/// `b1`, the unnormalised `p × a` and `|p × a|` (shared with the Jacobian).
fn basis_first(p: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>, f64) {
    let a = axis(p);
    let b1_raw = p.cross(&a);
    let norm = b1_raw.norm();
    (b1_raw / norm, a, norm)
}

/// The coordinate axis with the smallest `|p_i|`, ties resolved x, y, z as
/// GTSAM does.
fn axis(p: &Vector3<f64>) -> Vector3<f64> {
    let (mx, my, mz) = (p.x.abs(), p.y.abs(), p.z.abs());
    if mx <= my && mx <= mz {
        Vector3::x()
    } else if my <= mx && my <= mz {
        Vector3::y()
    } else {
        Vector3::z()
    }
}

/// Sphere exponential `Exp_p(B v) = cos θ p + (sin θ / θ) B v`, `θ = |B v|`
/// (GTSAM `Unit3::retract`), renormalised against round-off.
pub fn retract(p: &Vector3<f64>, v: &Vector2<f64>) -> Vector3<f64> {
    let xi = basis(p) * v;
    let theta = xi.norm();
    if theta < f64::EPSILON {
        return (p + xi).normalize();
    }
    (p * theta.cos() + xi * (theta.sin() / theta)).normalize()
}

/// `θ / sin θ` with `x = cos θ` and its derivative in `x`; a Taylor series
/// near `x = 1` where the closed form cancels.
fn theta_over_sin(x: f64) -> (f64, f64) {
    if x > 1.0 - 1e-5 {
        let e = x - 1.0;
        (
            1.0 - e / 3.0 + 2.0 * e * e / 15.0,
            -1.0 / 3.0 + 4.0 * e / 15.0,
        )
    } else {
        let s2 = 1.0 - x * x;
        let y = x.acos() / s2.sqrt();
        (y, (x * y - 1.0) / s2)
    }
}

/// Cosine below which `p` and `q` count as antipodal: the logarithm is not
/// unique there, GTSAM returns `(π, 0)` and so do we.
const ANTIPODAL: f64 = -1.0 + 1e-12;

/// Inverse of [`retract`]: `v` with `retract(p, v) = q` (GTSAM
/// `Unit3::localCoordinates`): `Bᵀ (θ / sin θ) (q − (p·q) p)`.
pub fn local_coordinates(p: &Vector3<f64>, q: &Vector3<f64>) -> Vector2<f64> {
    local_coordinates_with_jacobian(p, q).0
}

/// [`local_coordinates`] and its Jacobian with respect to `p` as a 3-vector
/// (only its action on tangent directions `δp ⊥ p` is meaningful).
///
/// With `x = p·q`, `y = θ / sin θ`, `w = y (q − x p)`, `f = Bᵀ(p) w`:
/// `∂w/∂p = y'(x) (q − x p) qᵀ − y p qᵀ − y x I`,
/// `∂b1/∂p = (I − b1 b1ᵀ) / |p × a| · (−[a]×)`,
/// `∂b2/∂p = −[b1]× + [p]× ∂b1/∂p`, so
/// `∂f_k/∂p = wᵀ ∂b_k/∂p + b_kᵀ ∂w/∂p`.
pub fn local_coordinates_with_jacobian(
    p: &Vector3<f64>,
    q: &Vector3<f64>,
) -> (Vector2<f64>, Matrix2x3<f64>) {
    let x = p.dot(q).clamp(-1.0, 1.0);
    if x < ANTIPODAL {
        return (Vector2::new(std::f64::consts::PI, 0.0), Matrix2x3::zeros());
    }
    let (y, dy) = theta_over_sin(x);
    let (b1, a, b1_norm) = basis_first(p);
    let b2 = p.cross(&b1);
    let v = q - p * x;
    let w = v * y;
    let value = Vector2::new(b1.dot(&w), b2.dot(&w));

    let dw = v * q.transpose() * dy - p * q.transpose() * y - Matrix3::identity() * (y * x);
    let db1 = (Matrix3::identity() - b1 * b1.transpose()) * (-hat(&a)) / b1_norm;
    let db2 = -hat(&b1) + hat(p) * db1;
    let row1 = w.transpose() * db1 + b1.transpose() * dw;
    let row2 = w.transpose() * db2 + b2.transpose() * dw;
    let mut jac = Matrix2x3::zeros();
    jac.row_mut(0).copy_from(&row1);
    jac.row_mut(1).copy_from(&row2);
    (value, jac)
}

/// GTSAM's `Unit3::errorVector`: `Bᵀ(p) q`, the tangent-plane projection of
/// `q` at `p` (norm `sin θ`), and its Jacobian with respect to `p` as a
/// 3-vector: `∂(b_kᵀ q)/∂p = qᵀ ∂b_k/∂p` (the basis derivatives of
/// [`local_coordinates_with_jacobian`]). This, not `localCoordinates`, is the
/// normal residual of GTSAM's `OrientedPlane3Factor`.
pub fn error_vector_with_jacobian(
    p: &Vector3<f64>,
    q: &Vector3<f64>,
) -> (Vector2<f64>, Matrix2x3<f64>) {
    let (b1, a, b1_norm) = basis_first(p);
    let b2 = p.cross(&b1);
    let db1 = (Matrix3::identity() - b1 * b1.transpose()) * (-hat(&a)) / b1_norm;
    let db2 = -hat(&b1) + hat(p) * db1;
    let mut jac = Matrix2x3::zeros();
    jac.row_mut(0).copy_from(&(q.transpose() * db1));
    jac.row_mut(1).copy_from(&(q.transpose() * db2));
    (Vector2::new(b1.dot(q), b2.dot(q)), jac)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_and_tangent() {
        for p in [
            Vector3::new(0.3, -0.5, 0.8).normalize(),
            Vector3::z(),
            Vector3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let b = basis(&p);
            assert!((b.transpose() * b - nalgebra::Matrix2::identity()).norm() < 1e-14);
            assert!((b.transpose() * p).norm() < 1e-15);
        }
    }

    #[test]
    fn local_inverts_retract() {
        let p = Vector3::new(0.2, 0.9, -0.1).normalize();
        let v = Vector2::new(0.3, -0.7);
        let q = retract(&p, &v);
        assert!((local_coordinates(&p, &q) - v).norm() < 1e-12);
        assert_eq!(
            local_coordinates(&p, &-p),
            Vector2::new(std::f64::consts::PI, 0.0)
        );
    }
}
