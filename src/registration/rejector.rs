//! Mismatch removal: which candidate pairs agree on one transform.
//!
//! The paper's rejector ([`GroundTripleRansac`]) computes the closed-form
//! transform of every triple of pairs that includes the ground pair (the
//! ground is extracted separately so that one of three non-parallel planes
//! is always known), counts the pairs each transform explains, and keeps
//! the best. Without a ground pair any triple is tried. Samples need two
//! non-parallel normals for the rotation; where a triple leaves a
//! translation direction free (a corridor: floor plus two parallel walls)
//! the prior supplies it, so a degenerate scene still yields a hypothesis.
//! All triples are enumerated when there are at most `max_hypotheses`;
//! beyond that a seeded random subset is drawn.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use super::closed_form::closed_form;
use super::Correspondence;
use crate::rng::SplitMix64;

/// Mismatch rejectors selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RejectorName {
    /// RANSAC over triples that include the ground pair (the paper).
    GroundTripleRansac,
    /// Keep every pair (an ablation: what RANSAC buys).
    None,
}

/// Settings of the mismatch rejection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RejectorParams {
    /// The rejector: the ground-constrained triple RANSAC in every
    /// configuration (no key).
    #[serde(skip, default = "ground_triple_ransac")]
    pub name: RejectorName,
    /// A pair is an inlier of a transform when the moved source normal is
    /// within this angle of the target normal, degrees.
    pub inlier_angle_deg: f64,
    /// ... and the offsets differ by at most this, m.
    pub inlier_offset: f64,
    /// Two normals closer than this angle count as parallel, degrees.
    pub min_pair_angle_deg: f64,
    /// Enumerate all triples up to this many, else sample this many:
    /// [`MAX_HYPOTHESES`].
    #[serde(skip, default = "max_hypotheses")]
    pub max_hypotheses: usize,
    /// Eigenvalue of `AᵀA` below which a translation direction is left to
    /// the prior in the closed form (a sum of squared unit-normal
    /// components, dimensionless).
    pub min_eigenvalue: f64,
}

/// Triples of plane pairs: all of them up to this many, else this many
/// sampled.
pub const MAX_HYPOTHESES: usize = 2000;

fn max_hypotheses() -> usize {
    MAX_HYPOTHESES
}

fn ground_triple_ransac() -> RejectorName {
    RejectorName::GroundTripleRansac
}

impl Default for RejectorParams {
    /// `[slam.rejector]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.rejector")
    }
}

impl RejectorParams {
    /// Cosine of the inlier angle.
    pub fn inlier_cos(&self) -> f64 {
        self.inlier_angle_deg.to_radians().cos()
    }
}

/// The consistent pairs and the transform they agree on.
#[derive(Debug, Clone, PartialEq)]
pub struct Consensus {
    /// The hypothesis transform (source to target).
    pub pose: Isometry3<f64>,
    /// Indices of the pairs it explains, ascending.
    pub inliers: Vec<usize>,
}

/// Removes mismatched pairs. Implementations are selected by name in the
/// configuration ([`RejectorParams::name`], no key).
pub trait MismatchRejector: Send + Sync {
    /// The name this rejector is selected by.
    fn name(&self) -> &'static str;

    /// The pairs that agree on one transform and that transform, or `None`
    /// when no hypothesis can be formed. `prior` is the expected transform
    /// (it fills undetermined translation directions); `seed` makes any
    /// sampling deterministic.
    fn reject(
        &self,
        pairs: &[Correspondence],
        prior: &Isometry3<f64>,
        seed: u64,
    ) -> Option<Consensus>;
}

/// The paper's RANSAC over plane triples anchored on the ground pair.
#[derive(Debug, Clone, Default)]
pub struct GroundTripleRansac {
    params: RejectorParams,
}

impl GroundTripleRansac {
    /// A rejector with the given settings.
    pub fn new(params: RejectorParams) -> Self {
        Self { params }
    }

    /// Whether the sample's normals determine a rotation: two of them at
    /// least `min_pair_angle_deg` apart.
    fn spans_two_directions(&self, sample: &[Correspondence]) -> bool {
        let max_cos = self.params.min_pair_angle_deg.to_radians().cos();
        sample.iter().enumerate().any(|(i, a)| {
            sample[i + 1..]
                .iter()
                .any(|b| a.source.normal.dot(&b.source.normal).abs() < max_cos)
        })
    }
}

/// The index triples to try: with ground pairs, each ground pair with
/// every two other pairs; without, every triple; with two pairs, the pair.
fn samples(pairs: &[Correspondence]) -> (Vec<usize>, usize) {
    let ground: Vec<usize> = (0..pairs.len()).filter(|&i| pairs[i].ground).collect();
    let others: Vec<usize> = (0..pairs.len()).filter(|&i| !pairs[i].ground).collect();
    let n = pairs.len();
    let count = if n < 3 {
        usize::from(n == 2)
    } else if !ground.is_empty() {
        let m = others.len();
        ground.len() * (m * m.saturating_sub(1) / 2)
    } else {
        n * (n - 1) * (n - 2) / 6
    };
    (ground, count)
}

impl MismatchRejector for GroundTripleRansac {
    fn name(&self) -> &'static str {
        "ground-triple-ransac"
    }

    fn reject(
        &self,
        pairs: &[Correspondence],
        prior: &Isometry3<f64>,
        seed: u64,
    ) -> Option<Consensus> {
        let p = &self.params;
        let n = pairs.len();
        if n < 2 {
            return None;
        }
        let (ground, total) = samples(pairs);
        let others: Vec<usize> = (0..n).filter(|&i| !pairs[i].ground).collect();
        let inlier_cos = p.inlier_cos();
        let mut best: Option<(usize, f64, Isometry3<f64>)> = None;
        let evaluate = |idx: &[usize], best: &mut Option<(usize, f64, Isometry3<f64>)>| {
            let sample: Vec<Correspondence> = idx.iter().map(|&i| pairs[i]).collect();
            if !self.spans_two_directions(&sample) {
                return;
            }
            let Some(t) = closed_form(&sample, prior, p.min_eigenvalue) else {
                return;
            };
            let mut count = 0;
            let mut err = 0.0;
            for c in pairs {
                if c.agrees(&t, inlier_cos, p.inlier_offset) {
                    count += 1;
                    let m = c.source.transformed(&t);
                    err += (m.d - c.target.d).abs() + (1.0 - m.normal.dot(&c.target.normal));
                }
            }
            let better = match best {
                None => count > 0,
                Some((bc, be, _)) => count > *bc || (count == *bc && err < *be),
            };
            if better {
                *best = Some((count, err, t));
            }
        };
        if n == 2 {
            evaluate(&[0, 1], &mut best);
        } else if total <= p.max_hypotheses {
            if ground.is_empty() {
                for i in 0..n {
                    for j in i + 1..n {
                        for k in j + 1..n {
                            evaluate(&[i, j, k], &mut best);
                        }
                    }
                }
            } else {
                for &g in &ground {
                    for (a, &i) in others.iter().enumerate() {
                        for &j in &others[a + 1..] {
                            evaluate(&[g, i, j], &mut best);
                        }
                    }
                }
            }
        } else {
            let mut rng = SplitMix64::new(seed);
            for _ in 0..p.max_hypotheses {
                let idx = if ground.is_empty() || others.len() < 2 {
                    [rng.below(n), rng.below(n), rng.below(n)]
                } else {
                    [
                        ground[rng.below(ground.len())],
                        others[rng.below(others.len())],
                        others[rng.below(others.len())],
                    ]
                };
                if idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] {
                    continue;
                }
                evaluate(&idx, &mut best);
            }
        }
        let (_, _, pose) = best?;
        let inliers = (0..n)
            .filter(|&i| pairs[i].agrees(&pose, inlier_cos, p.inlier_offset))
            .collect();
        Some(Consensus { pose, inliers })
    }
}

/// Keeps every pair; the hypothesis is the closed form over all of them
/// (or the prior when it is undetermined).
#[derive(Debug, Clone, Default)]
pub struct AcceptAll {
    params: RejectorParams,
}

impl AcceptAll {
    /// A pass-through rejector (`min_eigenvalue` is used by the closed form).
    pub fn new(params: RejectorParams) -> Self {
        Self { params }
    }
}

impl MismatchRejector for AcceptAll {
    fn name(&self) -> &'static str {
        "none"
    }

    fn reject(
        &self,
        pairs: &[Correspondence],
        prior: &Isometry3<f64>,
        _seed: u64,
    ) -> Option<Consensus> {
        if pairs.is_empty() {
            return None;
        }
        let pose = closed_form(pairs, prior, self.params.min_eigenvalue).unwrap_or(*prior);
        Some(Consensus {
            pose,
            inliers: (0..pairs.len()).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;
    use nalgebra::Vector3;

    fn pair(n: Vector3<f64>, d: f64, t: &Isometry3<f64>, ground: bool) -> Correspondence {
        let source = Plane::new(n, d).unwrap();
        Correspondence {
            source,
            target: source.transformed(t),
            ground,
            source_index: 0,
            target_index: 0,
        }
    }

    #[test]
    fn ransac_drops_a_mismatch_and_recovers_the_transform() {
        let t = Isometry3::new(Vector3::new(0.1, -0.05, 0.0), Vector3::new(0.0, 0.0, 0.05));
        let mut pairs = vec![
            pair(Vector3::z(), 1.2, &t, true),
            pair(Vector3::x(), 3.0, &t, false),
            pair(Vector3::y(), 2.0, &t, false),
            pair(-Vector3::x(), 4.0, &t, false),
        ];
        // A mismatch: a wall paired with a wall 0.08 m further and turned.
        let mut bad = pair(Vector3::new(1.0, 1.0, 0.0), 2.5, &t, false);
        bad.target = Plane::new(Vector3::new(1.0, 0.6, 0.0), 2.9).unwrap();
        pairs.insert(2, bad);
        let c = GroundTripleRansac::default()
            .reject(&pairs, &Isometry3::identity(), 1)
            .unwrap();
        assert_eq!(c.inliers, vec![0, 1, 3, 4]);
        assert!(c.pose.rotation.angle_to(&t.rotation) < 1e-9);
        assert!((c.pose.translation.vector - t.translation.vector).norm() < 1e-9);
    }

    #[test]
    fn the_sample_count_follows_the_ground_anchor() {
        let t = Isometry3::identity();
        let mut pairs: Vec<_> = (0..6)
            .map(|k| pair(Vector3::new(1.0, k as f64, 0.3), 2.0, &t, false))
            .collect();
        assert_eq!(samples(&pairs).1, 20);
        pairs[0].ground = true;
        assert_eq!(samples(&pairs).1, 10);
        assert_eq!(samples(&pairs[..2]).1, 1);
    }
}
