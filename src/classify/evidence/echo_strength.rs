//! Echo strength against the landmark's reflected and transmitted echoes.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;
use crate::reflect::echo_split::echo_strength;

/// A reflection off glass comes back scaled by `R²`, a transmitted echo by
/// `T²`: where the echoes behind a landmark fall in two groups
/// ([`EchoSplit`](crate::reflect::EchoSplit)), a point's strength is weighed
/// as a Gaussian in each group (log-strength, decades).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EchoStrength {
    /// Spread of the echo strengths within one group, decades: surface
    /// albedo (0.1-0.9 is a decade) and incidence.
    pub spread: f64,
    /// Probability that an echo falls on the other group's side whatever its
    /// distance from the threshold (a dark object behind glass, a bright
    /// one reflected): caps the weight.
    pub error: f64,
}

impl Default for EchoStrength {
    fn default() -> Self {
        Self {
            spread: 0.3,
            error: 0.05,
        }
    }
}

impl EvidenceTest for EchoStrength {
    fn name(&self) -> &str {
        "echo-strength"
    }

    fn rule(&self) -> Rule {
        Rule::EchoStrength
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let split = point.landmark.echo_split.filter(|_| point.single_pane)?;
        let cos = if split.incidence_correction {
            point.scan.incidence_cos(point.frame, point.index).unwrap_or(1.0)
        } else {
            1.0
        };
        let s = echo_strength(point.intensity(), point.range, split.range_exponent, cos);
        let (reflected, transmitted) = if split.weak_is_reflection {
            (split.weak_mean, split.strong_mean)
        } else {
            (split.strong_mean, split.weak_mean)
        };
        let var = 2.0 * self.spread * self.spread;
        let llr = ((s - transmitted).powi(2) - (s - reflected).powi(2)) / var;
        let cap = outcome_weight(self.error);
        Some(llr.clamp(-cap, cap))
    }
}
