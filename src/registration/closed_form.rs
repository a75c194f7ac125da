//! The closed-form transform of plane pairs (after Taguchi et al. 2013,
//! planes only).
//!
//! Rotation and translation decouple. The rotation minimises
//! `Σ ‖R n_s − n_t‖²`: with `H = Σ n_s n_tᵀ = U Σ Vᵀ`, `R = V D Uᵀ` where
//! `D = diag(1, 1, det(V Uᵀ))` on the singular values in descending order —
//! the determinant correction keeps a reflection from coming out when the
//! normals are (nearly) coplanar. It is unique when the source normals span
//! at least two directions.
//!
//! The translation minimises `Σ (n_tᵀ t − (d_s − d_t))²`: with `A` the
//! stacked target normals and `b = d_s − d_t`, `t = A⁺ b`. We solve it as a
//! correction to a prior, `t = t₀ + A⁺ (b − A t₀)`, with the pseudo-inverse
//! cut at `min_eigenvalue` of `AᵀA`: in directions no normal constrains
//! (a corridor's axis) the prior's translation is kept instead of the
//! minimum-norm answer, which would silently put the sensor back to zero
//! motion along them.

use nalgebra::{
    Isometry3, Matrix3, Rotation3, SymmetricEigen, Translation3, UnitQuaternion, Vector3,
};

use super::Correspondence;

/// Singular-value ratio `σ₂ / σ₁` of `H` below which the normals are
/// considered parallel and the rotation undetermined.
const MIN_SINGULAR_RATIO: f64 = 1e-3;

/// The rotation that best maps the source normals onto the target normals,
/// or `None` when the normals do not span two directions.
pub fn rotation(pairs: &[Correspondence]) -> Option<UnitQuaternion<f64>> {
    let mut h = Matrix3::zeros();
    for c in pairs {
        h += c.source.normal * c.target.normal.transpose();
    }
    if !h.iter().all(|v| v.is_finite()) {
        return None;
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let s = svd.singular_values;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
    if !(s[order[1]] > MIN_SINGULAR_RATIO * s[order[0]]) {
        return None;
    }
    let v = v_t.transpose();
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        // Flip the axis of the smallest singular value: the closest proper
        // rotation instead of a reflection.
        d[(order[2], order[2])] = -1.0;
    }
    let r = v * d * u.transpose();
    Some(UnitQuaternion::from_rotation_matrix(
        &Rotation3::from_matrix_unchecked(r),
    ))
}

/// The translation for a known rotation, as a correction of `prior` (see
/// the module documentation); also returns how many directions the pairs
/// determine (the rank of `AᵀA` at `min_eigenvalue`).
pub fn translation(
    pairs: &[Correspondence],
    prior: &Vector3<f64>,
    min_eigenvalue: f64,
) -> (Vector3<f64>, usize) {
    let mut ata = Matrix3::zeros();
    let mut atr = Vector3::zeros();
    for c in pairs {
        let n = c.target.normal;
        let r = c.source.d - c.target.d - n.dot(prior);
        ata += n * n.transpose();
        atr += n * r;
    }
    if !(ata.iter().all(|v| v.is_finite()) && atr.iter().all(|v| v.is_finite())) {
        return (*prior, 0);
    }
    let eig = SymmetricEigen::new(ata);
    let mut delta = Vector3::zeros();
    let mut rank = 0;
    for k in 0..3 {
        let lambda = eig.eigenvalues[k];
        if lambda > min_eigenvalue {
            let v = eig.eigenvectors.column(k);
            delta += v * (v.dot(&atr) / lambda);
            rank += 1;
        }
    }
    (prior + delta, rank)
}

/// The closed-form transform (source to target) of `pairs`, with `prior`
/// supplying the translation in undetermined directions. `None` when the
/// rotation is undetermined (fewer than two non-parallel normals).
pub fn closed_form(
    pairs: &[Correspondence],
    prior: &Isometry3<f64>,
    min_eigenvalue: f64,
) -> Option<Isometry3<f64>> {
    let rotation = rotation(pairs)?;
    let (t, _) = translation(pairs, &prior.translation.vector, min_eigenvalue);
    Some(Isometry3::from_parts(Translation3::from(t), rotation))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::registration::test_pair as pair;

    #[test]
    fn coplanar_normals_give_a_rotation_not_a_reflection() {
        // Two normals in the xy plane: H has rank 2 and V Uᵀ may be a
        // reflection; the determinant check must return the true rotation.
        let t = Isometry3::new(Vector3::new(0.1, 0.2, 0.0), Vector3::new(0.0, 0.0, 0.3));
        let pairs = [
            pair(Vector3::x(), 2.0, &t),
            pair(Vector3::y(), 3.0, &t),
            pair(-Vector3::x(), 4.0, &t),
        ];
        let r = rotation(&pairs).unwrap();
        assert!(r.angle_to(&t.rotation) < 1e-9);
        assert!(r.to_rotation_matrix().matrix().determinant() > 0.0);
    }

    #[test]
    fn undetermined_translation_keeps_the_prior() {
        // Floor, ceiling and two parallel walls: nothing constrains x.
        let t = Isometry3::new(Vector3::new(0.5, 0.2, -0.1), Vector3::zeros());
        let pairs = [
            pair(Vector3::z(), 1.0, &t),
            pair(-Vector3::z(), 2.0, &t),
            pair(Vector3::y(), 1.5, &t),
            pair(-Vector3::y(), 1.2, &t),
        ];
        let prior = Vector3::new(0.3, 0.0, 0.0);
        let (tr, rank) = translation(&pairs, &prior, 1e-6);
        assert_eq!(rank, 2);
        assert!((tr - Vector3::new(0.3, 0.2, -0.1)).norm() < 1e-12, "{tr}");
    }

    #[test]
    fn parallel_normals_have_no_rotation() {
        let t = Isometry3::identity();
        let pairs = [pair(Vector3::z(), 1.0, &t), pair(-Vector3::z(), 2.0, &t)];
        assert!(rotation(&pairs).is_none());
    }
}
