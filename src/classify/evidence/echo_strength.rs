//! Echo strength against the landmark's reflected and transmitted echoes.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;
use crate::reflect::echo_split::echo_strength;

/// A reflection off glass comes back scaled by `R²`, a transmitted echo by
/// `T²`: where the echoes behind a landmark fall in two groups
/// ([`EchoSplit`](crate::reflect::EchoSplit)), a point's strength is weighed
/// as a Gaussian in each group (log-strength, decades, with the group's own
/// mean and spread): groups that overlap weigh little.
///
/// Behind a second pane as well: a reflection in the landmark (the nearer
/// pane) keeps its `R²` wherever it appears, and a second clear pane takes
/// a transmitted echo down by its own `T²` only (0.07-0.31 decades for
/// `T` 0.70-0.92), far less than a clear pane's groups lie apart (1.3-2.7
/// decades). The "second pane" is often no pane: a facade seen through the
/// window, made a plane by its near returns where the glass gave no echo.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EchoStrength {
    /// Probability that a real echo falls deep in the reflected group (a
    /// dark or distant object behind glass): caps the weight towards a
    /// reflection.
    pub weak_error: f64,
    /// Share of a landmark's echoes that fall outside their own group
    /// where both groups are fitted to its echoes (a surface darker or
    /// brighter than the rest, a bright surface reflected): an echo then
    /// weighs at most about `ln(1 / fitted_error)` either way.
    pub fitted_error: f64,
}

/// The strengths an outlier of a fitted group may take, spread evenly over
/// this many decades (about the span of echo strengths a sensor reports).
const OUTLIER_SPAN: f64 = 4.0;

impl EchoStrength {
    /// The density of strength `s` in a fitted group `(mean, spread)`,
    /// with its outliers ([`fitted_error`](Self::fitted_error)).
    fn fitted_density(&self, s: f64, (mean, spread): (f64, f64)) -> f64 {
        let z = (s - mean) / spread;
        let gauss = (-0.5 * z * z).exp() / (spread * (2.0 * std::f64::consts::PI).sqrt());
        (1.0 - self.fitted_error) * gauss + self.fitted_error / OUTLIER_SPAN
    }
}

/// The least spread of the echo strengths within one group, decades: the
/// histogram's resolution (0.05) and the range noise, where a group's own
/// spread is narrower.
const MIN_SPREAD: f64 = 0.1;

/// The values of `configs/default.toml`.
impl Default for EchoStrength {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.echo_strength")
    }
}

impl EvidenceTest for EchoStrength {
    fn name(&self) -> &str {
        "echo-strength"
    }

    fn rule(&self) -> Rule {
        Rule::EchoStrength
    }

    fn tells_the_path(&self) -> bool {
        true
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let split = point.landmark.echo_split?;
        let level = || {
            point
                .space
                .and_then(|s| s.level_incidence_cos(&point.position))
        };
        let cos = split.incidence_cos(point.scan, point.frame, point.index, level);
        let s = echo_strength(point.intensity(), point.range, split.range_exponent, cos);
        let weak = (split.weak_mean, split.weak_spread.max(MIN_SPREAD));
        let strong = (split.strong_mean, split.strong_spread.max(MIN_SPREAD));
        let (reflected, transmitted) = if split.weak_is_reflection {
            (weak, strong)
        } else {
            (strong, weak)
        };
        // Behind a mirror the images are as strong as the room: the
        // strengths tell glass's reflections from its transmissions only.
        let glass = 1.0 - point.landmark.mirror_probability.unwrap_or(0.0);
        // Groups fitted to this landmark's own echoes: each echo weighs by
        // their densities, outliers of either group allowed for.
        if !split.from_physics {
            let density = |group| self.fitted_density(s, group);
            return Some(glass * (density(reflected) / density(transmitted)).ln());
        }
        // A split not fitted to this landmark's echoes cannot tell a
        // transmission from a reflection off coated glass (`R` close to
        // `T`): a strong echo is no evidence, only a weak one is.
        let llr = glass * (log_gauss(s, reflected) - log_gauss(s, transmitted));
        Some(llr.clamp(0.0, outcome_weight(self.weak_error)))
    }
}

/// `ln N(x; mean, sd)` up to the constant both groups share.
fn log_gauss(x: f64, (mean, sd): (f64, f64)) -> f64 {
    -0.5 * ((x - mean) / sd).powi(2) - sd.ln()
}
