//! Property tests of plane registration and trajectory alignment: the
//! closed form recovers rigid transforms, the Gauss–Newton Jacobian matches
//! central differences on the manifold, Umeyama recovers alignments.

use nalgebra::{Isometry3, Matrix4x6, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use proptest::prelude::*;
use specular::eval::umeyama;
use specular::geometry::{se3, Plane};
use specular::registration::closed_form::closed_form;
use specular::registration::gauss_newton::{jacobian, refine, residual, GaussNewtonParams};
use specular::registration::Correspondence;

fn vec3(r: f64) -> impl Strategy<Value = Vector3<f64>> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// Rigid transforms with rotations up to 3 rad (any axis).
fn isometry() -> impl Strategy<Value = Isometry3<f64>> {
    (vec3(10.0), vec3(1.7)).prop_map(|(t, w)| {
        Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(w))
    })
}

/// 3 to 8 planes whose normals span all three directions well (the
/// smallest singular value of the stacked normals is at least 0.3).
fn planes() -> impl Strategy<Value = Vec<Plane>> {
    prop::collection::vec((vec3(1.0), 0.5..15.0f64), 3..8).prop_filter_map(
        "normals must span 3-D",
        |raw| {
            let planes: Vec<Plane> = raw
                .into_iter()
                .filter_map(|(n, d)| (n.norm() > 0.2).then(|| Plane::new(n, d)).flatten())
                .collect();
            if planes.len() < 3 {
                return None;
            }
            let mut m = nalgebra::Matrix3::zeros();
            for p in &planes {
                m += p.normal * p.normal.transpose();
            }
            let smallest = m.symmetric_eigenvalues().min();
            (smallest > 0.3).then_some(planes)
        },
    )
}

fn pairs(planes: &[Plane], t: &Isometry3<f64>) -> Vec<Correspondence> {
    planes
        .iter()
        .enumerate()
        .map(|(k, p)| Correspondence {
            source: *p,
            target: p.transformed(t),
            ground: false,
            source_index: k,
            target_index: k,
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The closed form recovers a random rigid transform from noise-free
    /// pairs of non-parallel planes (any prior: nothing is undetermined).
    #[test]
    fn closed_form_recovers_the_transform(t in isometry(), ps in planes(), prior in isometry()) {
        let got = closed_form(&pairs(&ps, &t), &prior, 1e-6).expect("determined");
        prop_assert!(got.rotation.angle_to(&t.rotation) < 1e-8, "{got:?} vs {t:?}");
        prop_assert!((got.translation.vector - t.translation.vector).norm() < 1e-7);
        prop_assert!(got.rotation.to_rotation_matrix().matrix().determinant() > 0.0);
    }

    /// Gauss–Newton from the closed form stays at the exact solution, and
    /// from a perturbed start returns to it.
    #[test]
    fn gauss_newton_returns_to_the_solution(t in isometry(), ps in planes(), d in vec3(0.2), w in vec3(0.1)) {
        let pairs = pairs(&ps, &t);
        let start = se3::retract(&t, &Vector6::new(d.x, d.y, d.z, w.x, w.y, w.z));
        let r = refine(&pairs, &start, &GaussNewtonParams { degeneracy_threshold: 1e-9, ..Default::default() });
        prop_assert!(se3::local(&t, &r.pose).norm() < 1e-7, "{:?}", se3::local(&t, &r.pose));
    }

    /// The analytic Jacobian of the paper's residual equals central
    /// differences on the manifold: `(e(T exp(h eₖ)) − e(T exp(−h eₖ))) / 2h`.
    #[test]
    fn jacobian_matches_central_differences(t in isometry(), p in (vec3(1.0), -10.0..10.0f64), q in (vec3(1.0), -10.0..10.0f64)) {
        let (Some(source), Some(target)) = (Plane::new(p.0, p.1), Plane::new(q.0, q.1)) else {
            return Ok(());
        };
        let c = Correspondence { source, target, ground: false, source_index: 0, target_index: 0 };
        let analytic = jacobian(&t, &c);
        let h = 1e-6;
        let mut numeric = Matrix4x6::zeros();
        for k in 0..6 {
            let mut dv = Vector6::zeros();
            dv[k] = h;
            let plus = residual(&se3::retract(&t, &dv), &c);
            let minus = residual(&se3::retract(&t, &(-dv)), &c);
            numeric.set_column(k, &((plus - minus) / (2.0 * h)));
        }
        let scale = 1.0 + t.translation.vector.norm();
        prop_assert!((analytic - numeric).amax() < 1e-6 * scale, "analytic {analytic} numeric {numeric}");
    }

    /// Umeyama (no scale) recovers a known alignment of a random point set.
    #[test]
    fn umeyama_recovers_a_known_alignment(t in isometry(), pts in prop::collection::vec(vec3(20.0), 4..40)) {
        let source: Vec<Point3<f64>> = pts.into_iter().map(Point3::from).collect();
        // Skip nearly collinear sets (rotation about their line is free).
        let mean = source.iter().map(|p| p.coords).sum::<Vector3<f64>>() / source.len() as f64;
        let mut cov = nalgebra::Matrix3::zeros();
        for p in &source {
            let r = p.coords - mean;
            cov += r * r.transpose();
        }
        prop_assume!(cov.symmetric_eigenvalues().iter().filter(|&&l| l > 1.0).count() >= 2);
        let target: Vec<Point3<f64>> = source.iter().map(|p| t * p).collect();
        let got = umeyama(&source, &target).expect("alignment");
        prop_assert!(got.rotation.angle_to(&t.rotation) < 1e-8);
        prop_assert!((got.translation.vector - t.translation.vector).norm() < 1e-7);
    }
}
