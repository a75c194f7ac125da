//! Degeneracy: the directions of the pose that the matched planes leave
//! free.
//!
//! With the right-perturbation `T · exp(δ)`, `δ = (ρ, φ)`, the Gauss–Newton
//! information matrix `JᵀJ` has an eigenvalue near zero along every
//! direction no pair constrains. In a corridor (floor, ceiling and two
//! parallel walls) the translation along the corridor is such a direction:
//! its eigenvector is `(x̂, 0)` in the sensor frame. The solvers step only
//! in the span of the eigenvectors above the threshold and keep the prior
//! (the motion model) in the others, and the tracker reports them.

use nalgebra::{Isometry3, Matrix6, SymmetricEigen, Vector3, Vector6};

/// The eigen-analysis of an information matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct Degeneracy {
    /// Eigenvalues, ascending.
    pub eigenvalues: [f64; 6],
    /// Unit eigenvectors (tangent directions `(ρ, φ)`, sensor frame), same
    /// order as the eigenvalues.
    pub eigenvectors: [Vector6<f64>; 6],
    /// Eigenvalues at or below this are unobservable.
    pub threshold: f64,
}

impl Degeneracy {
    /// Analyse `information` (symmetric positive semi-definite); a matrix
    /// with non-finite entries observes nothing.
    pub fn of(information: &Matrix6<f64>, threshold: f64) -> Self {
        if !information.iter().all(|v| v.is_finite()) {
            return Self::none_observable(threshold);
        }
        let eig = SymmetricEigen::new(*information);
        let mut order = [0usize, 1, 2, 3, 4, 5];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        Self {
            eigenvalues: order.map(|k| eig.eigenvalues[k]),
            eigenvectors: order.map(|k| eig.eigenvectors.column(k).into_owned()),
            threshold,
        }
    }

    /// Fully degenerate (nothing observable): no pairs at all.
    pub fn none_observable(threshold: f64) -> Self {
        Self {
            eigenvalues: [0.0; 6],
            eigenvectors: std::array::from_fn(|k| {
                let mut v = Vector6::zeros();
                v[k] = 1.0;
                v
            }),
            threshold,
        }
    }

    /// Number of unobservable directions.
    pub fn count(&self) -> usize {
        self.eigenvalues
            .iter()
            .filter(|&&l| !(l > self.threshold))
            .count()
    }

    /// Whether any direction is unobservable.
    pub fn is_degenerate(&self) -> bool {
        self.count() > 0
    }

    /// The smallest eigenvalue.
    pub fn min_eigenvalue(&self) -> f64 {
        self.eigenvalues[0]
    }

    /// The unobservable directions (sensor-frame tangent vectors).
    pub fn directions(&self) -> impl Iterator<Item = &Vector6<f64>> + '_ {
        self.eigenvalues
            .iter()
            .zip(&self.eigenvectors)
            .filter(|(l, _)| !(**l > self.threshold))
            .map(|(_, v)| v)
    }

    /// The Gauss–Newton step `δ = −(JᵀJ)⁺ g` restricted to the observable
    /// subspace (`g = Jᵀe`).
    pub fn solve(&self, gradient: &Vector6<f64>) -> Vector6<f64> {
        let mut delta = Vector6::zeros();
        for (l, v) in self.eigenvalues.iter().zip(&self.eigenvectors) {
            if *l > self.threshold {
                delta -= v * (v.dot(gradient) / l);
            }
        }
        delta
    }

    /// A short description of the unobservable directions for reports:
    /// each as `t(x y z)` (a translation, world axes) or `r(x y z)` (a
    /// rotation axis, world axes), whichever part dominates, `;`-separated.
    pub fn describe(&self, pose: &Isometry3<f64>) -> String {
        self.directions()
            .map(|v| {
                let rho = Vector3::new(v[0], v[1], v[2]);
                let phi = Vector3::new(v[3], v[4], v[5]);
                let (tag, w) = if rho.norm() >= phi.norm() {
                    ("t", rho)
                } else {
                    ("r", phi)
                };
                let w = (pose.rotation * w).normalize();
                // A direction's sign is arbitrary: show the largest
                // component positive.
                let w = if w[w.iamax()] < 0.0 { -w } else { w };
                format!("{tag}({:.2} {:.2} {:.2})", w.x, w.y, w.z)
            })
            .collect::<Vec<_>>()
            .join(";")
    }
}
