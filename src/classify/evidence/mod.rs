//! Evidence weighed behind the glass: every point behind a reflective
//! landmark has two hypotheses, real where it was measured (an Obstacle seen
//! through glass) or the mirror image of a real point (a Reflection). Each
//! [`EvidenceTest`] returns the log-likelihood ratio of what it observes
//! under the two, from physical quantities (range noise, occupancy, echo
//! strengths); the landmark's glass-or-mirror probability gives the prior;
//! the posterior decides, and is the point's confidence. No test has the
//! last word: a strong echo behind a likely mirror and a mirror image on a
//! seen wall are weighed together.
//!
//! The tests the classifier uses are listed by name in the configuration
//! (`plane_map.weighing.tests`); a researcher adds one by implementing
//! [`EvidenceTest`] and handing it to [`Weighing::with_test`].

mod depth;
mod echo_order;
mod echo_strength;
mod frame_free_space;
mod image_support;
mod level_surface;
mod params;
mod point;
pub mod seen_space;
mod seen_surface;
mod seen_through;
mod weighing;

pub use self::depth::Depth;
pub use self::echo_order::EchoOrder;
pub use self::echo_strength::EchoStrength;
pub use self::frame_free_space::FrameFreeSpace;
pub(crate) use self::image_support::{moved_off, ImageLanding};
pub use self::image_support::{ImageSupport, ImageSupportTest};
pub use self::level_surface::LevelSurface;
pub use self::params::{WeighingParams, TEST_NAMES};
pub use self::point::BehindPoint;
pub use self::seen_space::SeenSpace;
pub use self::seen_surface::SeenSurface;
pub use self::seen_through::SeenThrough;
pub use self::weighing::{Posterior, Weighing};

use crate::classify::rule::Rule;

/// One test of a point behind a reflective landmark: what it observes,
/// weighed as `ln P(observation | Reflection) / P(observation | real)`.
/// Positive favours the mirror image, negative the point being real; `None`
/// when the test observes nothing for this point (no space seen there, no
/// echo split learned): it then does not count at all.
pub trait EvidenceTest: Send + Sync + std::fmt::Debug {
    /// The name the configuration lists it by.
    fn name(&self) -> &str;

    /// The rule reported for a point this test decided (the test that
    /// weighed most in the winning direction); custom tests report
    /// [`Rule::Weighed`].
    fn rule(&self) -> Rule {
        Rule::Weighed
    }

    /// Whether the weight is a likelihood ratio proper, its two rates
    /// measured over every point behind a landmark: it then adds to the
    /// landmark's own share of reflections, the prior of the points no
    /// test weighs. A test whose weight is the log-odds of its error rate
    /// measured alone carries the development split's base rate in it, and
    /// adds to even odds instead.
    fn is_likelihood_ratio(&self) -> bool {
        false
    }

    /// Whether the test tells the echo's path (reflected or transmitted),
    /// not whether a surface stands where it was measured. 3DRef labels a
    /// point by the latter: a reflection that lands on a surface behind the
    /// glass is an Obstacle. On a surface seen through the glass
    /// ([`BehindPoint::on_surface_seen_through`](BehindPoint)) such a test is not
    /// weighed.
    fn tells_the_path(&self) -> bool {
        false
    }

    /// The log-likelihood ratio of this test's observation of `point`.
    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64>;
}

/// The log-likelihood ratio of a binary observation whose outcome points
/// the wrong way with probability `error`: `ln((1 - error) / error)`, the
/// most any single outcome of that test can weigh.
pub fn outcome_weight(error: f64) -> f64 {
    let e = error.clamp(1e-6, 0.5);
    ((1.0 - e) / e).ln()
}

/// The log-likelihood ratio of an observation seen at `reflection_rate`
/// among the reflections behind a landmark and at `real_rate` among its
/// real points: `ln(reflection_rate / real_rate)`, both rates kept within
/// (1e-6, 1]. A test weighing it is a likelihood ratio proper
/// ([`EvidenceTest::is_likelihood_ratio`]).
pub fn rate_weight(reflection_rate: f64, real_rate: f64) -> f64 {
    let rate = |r: f64| r.clamp(1e-6, 1.0);
    (rate(reflection_rate) / rate(real_rate)).ln()
}

#[cfg(test)]
mod tests;
