//! The posterior of a point behind a reflective landmark: the landmark's
//! prior and every test's log-likelihood ratio, summed.

use super::{BehindPoint, EvidenceTest, WeighingParams};
use crate::classify::rule::Rule;
use crate::error::Error;

/// Probabilities are kept this far from 0 and 1, so that evidence can
/// always overrule a prior.
const PRIOR_FLOOR: f64 = 1e-3;

/// A point's posterior: the probability that it is a reflection, and the
/// rule to report (the test that weighed most towards the more probable
/// hypothesis; the landmark's prior when none did).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Posterior {
    /// P(Reflection | evidence).
    pub reflection: f64,
    /// What decided it.
    pub rule: Rule,
    /// P(Reflection) before the evidence, as weighed: a posterior past a
    /// plane's seen extent mixes the evidence against this prior.
    pub prior: f64,
}

/// The tests a classifier weighs, with the prior's parameters.
#[derive(Debug)]
pub struct Weighing {
    tests: Vec<Box<dyn EvidenceTest>>,
    threshold: f64,
    reflection_prior: f64,
}

/// A beam that crossed a landmark within this distance of its extent's edge
/// may have passed beside it, m (panes are fitted on 0.2 m evidence cells
/// and overreach by up to half of one): there the landmark's mirror
/// probability does not count.
pub const EDGE_MARGIN: f64 = 0.15;

impl Weighing {
    /// The tests `params.tests` names, each with its parameters; an unknown
    /// name is an error that lists the known ones.
    pub fn from_params(params: &WeighingParams) -> Result<Self, Error> {
        let mut tests: Vec<Box<dyn EvidenceTest>> = Vec::new();
        for name in &params.tests {
            tests.push(match name.as_str() {
                "seen-space" => Box::new(params.seen_space) as Box<dyn EvidenceTest>,
                "seen-surface" => Box::new(params.seen_surface),
                "image-support" => Box::new(
                    params
                        .image_support
                        .test(params.seen_space, params.level_surface.tolerance),
                ),
                "frame-free-space" => Box::new(params.frame_free_space),
                "depth" => Box::new(params.depth),
                "echo-strength" => Box::new(params.echo_strength),
                "echo-order" => Box::new(params.echo_order),
                "level-surface" => Box::new(params.level_surface),
                "seen-through" => Box::new(params.seen_through),
                other => {
                    return Err(Error::Config(format!(
                        "plane_map.weighing.tests: unknown evidence test {other:?} (known: {})",
                        super::params::TEST_NAMES.join(", ")
                    )))
                }
            });
        }
        if !(params.threshold >= 0.5 && params.threshold < 1.0) {
            return Err(Error::Config(format!(
                "plane_map.weighing.threshold must be in [0.5, 1), got {}",
                params.threshold
            )));
        }
        if !(params.reflection_prior > 0.0 && params.reflection_prior < 1.0) {
            return Err(Error::Config(format!(
                "plane_map.weighing.reflection_prior must be in (0, 1), got {}",
                params.reflection_prior
            )));
        }
        Ok(Self {
            tests,
            threshold: params.threshold,
            reflection_prior: params.reflection_prior,
        })
    }

    /// These tests and one more, weighed after them.
    pub fn with_test(mut self, test: Box<dyn EvidenceTest>) -> Self {
        self.tests.push(test);
        self
    }

    /// The names of the tests weighed, in order.
    pub fn test_names(&self) -> Vec<&str> {
        self.tests.iter().map(|t| t.name()).collect()
    }

    /// The posterior a class needs.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The probability that `point` is a reflection before any test: the
    /// share of reflections among its landmark's echoes where their
    /// strengths tell it; else its landmark a mirror (then it is one), or
    /// glass, whose share is, for a point that no test weighed (`weighed`
    /// false), that of the reflections among the landmark's echoes that
    /// the seen space decided, else the configured prior. A beam that met
    /// a second pane behind the first (its landmark, the nearer) takes the
    /// first's: it was reflected there as often as any beam through it,
    /// and a reflection in the second is a Reflection too, so the first's
    /// share is the lower bound (the configured prior instead left such
    /// points an unclassified tie). Only beside the landmark's extent is it
    /// the configured prior.
    fn prior(&self, point: &BehindPoint<'_>, weighed: bool) -> f64 {
        let landmark = point.landmark;
        let beside = !landmark.bounds(&point.crossing_point(), -EDGE_MARGIN);
        let mirror = landmark.mirror_probability.unwrap_or(0.0);
        let p = match landmark.reflection_share {
            _ if beside => self.reflection_prior,
            Some(share) => share,
            None => match landmark.decided_share.filter(|_| !weighed) {
                Some(decided) => mirror + (1.0 - mirror) * decided,
                None => mirror + (1.0 - mirror) * self.reflection_prior,
            },
        };
        p.clamp(PRIOR_FLOOR, 1.0 - PRIOR_FLOOR)
    }

    /// The posterior of `point`.
    pub fn weigh(&self, point: &BehindPoint<'_>) -> Posterior {
        let mut evidence = 0.0;
        let mut weighed = false;
        let (mut best_for, mut best_against) = ((0.0, Rule::Undecided), (0.0, Rule::Undecided));
        let on_surface = point.on_surface_seen_through;
        for test in &self.tests {
            if on_surface && test.tells_the_path() {
                continue;
            }
            let Some(llr) = test.weigh(point).filter(|l| l.is_finite()) else {
                continue;
            };
            weighed |= llr != 0.0 && !test.is_likelihood_ratio();
            evidence += llr;
            if llr > best_for.0 {
                best_for = (llr, test.rule());
            } else if -llr > best_against.0 {
                best_against = (-llr, test.rule());
            }
        }
        let prior = self.prior(point, weighed);
        let log_odds = (prior / (1.0 - prior)).ln() + evidence;
        let reflection = 1.0 / (1.0 + (-log_odds).exp());
        let rule = match (reflection > 0.5, best_for.1, best_against.1) {
            (true, Rule::Undecided, _) | (false, _, Rule::Undecided) => Rule::Prior,
            (true, rule, _) | (false, _, rule) => rule,
        };
        Posterior {
            reflection,
            rule,
            prior,
        }
    }
}

/// The default tests with their default parameters.
impl Default for Weighing {
    fn default() -> Self {
        Self::from_params(&WeighingParams::default()).expect("the defaults are valid")
    }
}
