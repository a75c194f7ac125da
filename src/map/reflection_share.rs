//! How many of the echoes behind one landmark are reflections, from their
//! strengths: the transmissions that the space seen directly confirms show
//! how strong this landmark's real echoes are; the rest of its echoes are
//! those and a second group, its reflections, whose share and strength are
//! fitted (expectation-maximization over the strength histogram).
//!
//! Every echo behind the landmark has a strength, so unlike the tests that
//! fire only where the sequence saw the space, this sample is not biased
//! towards the points that carry evidence. Where the reflections are as
//! strong as the real echoes (coated glass, a mirror's images of the same
//! room) the strengths cannot tell them apart: the fit says so (no
//! mixture) rather than guess.

use super::BehindEchoes;
use crate::reflect::EchoHistogram;

/// Confirmed transmissions needed to know how strong the landmark's real
/// echoes are (a few keyframes' worth behind a pane).
pub const MIN_TRANSMISSIONS: u64 = 200;

/// Echoes behind the landmark needed to fit the share.
pub const MIN_ECHOES: u64 = 500;

/// The reflected group must lie at least this many of either group's
/// spreads from the real one: nearer, or wider, it may as well be real
/// echoes that the confirmed sample missed (darker surfaces, the far side
/// of a room behind the glass).
const MIN_SEPARATION_SPREADS: f64 = 2.0;

/// The least spread of the real group, decades: the confirmed sample may
/// come from one surface behind the glass, the landmark's real echoes from
/// several.
const MIN_REAL_SPREAD: f64 = 0.15;

/// The least spread of the reflected group, decades (twice the histogram's
/// bin).
const MIN_REFLECTED_SPREAD: f64 = 0.1;

/// Where the fit starts the reflected group, decades from the real group's
/// mean: glass reflects less than it transmits (weaker), coated glass may
/// reflect more (stronger). The start of the higher likelihood is kept.
const STARTS: [f64; 2] = [-1.0, 0.5];

/// EM iterations at most; the fit stops earlier when the share settles.
const MAX_ITERATIONS: usize = 300;

/// One group of echo strengths: a Gaussian in decades.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthGroup {
    /// Mean strength, decades.
    pub mean: f64,
    /// Standard deviation, decades.
    pub spread: f64,
}

impl StrengthGroup {
    /// The Gaussian density at `x` (per decade).
    fn density(&self, x: f64) -> f64 {
        let z = (x - self.mean) / self.spread;
        (-0.5 * z * z).exp() / (self.spread * (2.0 * std::f64::consts::PI).sqrt())
    }
}

/// The echoes behind one landmark as real echoes and reflections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthMixture {
    /// The share of reflections among them.
    pub share: f64,
    /// The reflections' strengths.
    pub reflected: StrengthGroup,
    /// The real echoes' strengths (those of the confirmed transmissions).
    pub real: StrengthGroup,
}

impl StrengthMixture {
    /// The mixture of `behind`'s echoes inside the landmark's extent, the
    /// real group that of its confirmed transmissions; `None` with too few
    /// of either, or where the reflected group cannot be told from the
    /// real one.
    pub fn fit(behind: &BehindEchoes) -> Option<Self> {
        let (all, confirmed) = (&behind.inside, &behind.transmitted);
        if confirmed.total() < MIN_TRANSMISSIONS || all.total() < MIN_ECHOES {
            return None;
        }
        let (mean, spread) = mean_and_spread(confirmed)?;
        let real = StrengthGroup {
            mean,
            spread: spread.max(MIN_REAL_SPREAD),
        };
        let bins: Vec<(f64, f64)> = all.bins().filter(|&(_, c)| c > 0.0).collect();
        let (mixture, _) = STARTS
            .iter()
            .filter_map(|&offset| em(&bins, real, mean + offset))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let apart = (mixture.reflected.mean - real.mean).abs();
        let widest = real.spread.max(mixture.reflected.spread);
        (apart >= MIN_SEPARATION_SPREADS * widest).then_some(mixture)
    }
}

/// Mean and standard deviation of a histogram's strengths.
fn mean_and_spread(h: &EchoHistogram) -> Option<(f64, f64)> {
    let (mut n, mut sum, mut sq) = (0.0, 0.0, 0.0);
    for (x, c) in h.bins() {
        n += c;
        sum += c * x;
        sq += c * x * x;
    }
    if n <= 0.0 {
        return None;
    }
    let mean = sum / n;
    Some((mean, (sq / n - mean * mean).max(0.0).sqrt()))
}

/// EM of the share and the reflected group over the histogram `bins`
/// (strength, count), the real group fixed; the mixture and its
/// log-likelihood, `None` where the reflected group empties.
fn em(bins: &[(f64, f64)], real: StrengthGroup, start: f64) -> Option<(StrengthMixture, f64)> {
    let mut share = 0.3;
    let mut reflected = StrengthGroup {
        mean: start,
        spread: 0.3,
    };
    let total: f64 = bins.iter().map(|&(_, c)| c).sum();
    for _ in 0..MAX_ITERATIONS {
        let (mut w, mut wx, mut wxx) = (0.0, 0.0, 0.0);
        for &(x, c) in bins {
            let r = share * reflected.density(x);
            let responsibility = r / (r + (1.0 - share) * real.density(x)).max(f64::MIN_POSITIVE);
            w += c * responsibility;
            wx += c * responsibility * x;
            wxx += c * responsibility * x * x;
        }
        if w < 1.0 {
            return None;
        }
        let previous = share;
        share = w / total;
        let mean = wx / w;
        reflected = StrengthGroup {
            mean,
            spread: (wxx / w - mean * mean)
                .max(0.0)
                .sqrt()
                .max(MIN_REFLECTED_SPREAD),
        };
        if (share - previous).abs() < 1e-9 {
            break;
        }
    }
    let log_likelihood = bins
        .iter()
        .map(|&(x, c)| {
            c * (share * reflected.density(x) + (1.0 - share) * real.density(x))
                .max(f64::MIN_POSITIVE)
                .ln()
        })
        .sum();
    let mixture = StrengthMixture {
        share,
        reflected,
        real,
    };
    Some((mixture, log_likelihood))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `n` echoes spread as a Gaussian of `mean` and `spread` (decades),
    /// counted bin by bin (0.05 decades) into `h`.
    fn add_group(h: &mut EchoHistogram, n: f64, mean: f64, spread: f64) {
        let group = StrengthGroup { mean, spread };
        let mut x = mean - 5.0 * spread;
        while x < mean + 5.0 * spread {
            let count = (n * group.density(x) * 0.05).round() as usize;
            for _ in 0..count {
                h.add(x);
            }
            x += 0.05;
        }
    }

    /// The echoes behind a landmark: `real` real echoes (a tenth of them
    /// confirmed) and `reflected` reflections.
    fn behind(real: (f64, f64, f64), reflected: (f64, f64, f64)) -> BehindEchoes {
        let mut b = BehindEchoes::default();
        add_group(&mut b.inside, real.0, real.1, real.2);
        add_group(&mut b.inside, reflected.0, reflected.1, reflected.2);
        add_group(&mut b.transmitted, real.0 / 10.0, real.1, real.2);
        b
    }

    #[test]
    fn weak_glass_reflections_are_found_with_their_share() {
        let m = StrengthMixture::fit(&behind((7000.0, 3.5, 0.2), (3000.0, 2.3, 0.25))).unwrap();
        assert!((m.share - 0.3).abs() < 0.02, "{m:?}");
        assert!((m.reflected.mean - 2.3).abs() < 0.05, "{m:?}");
        assert!(m.reflected.mean < m.real.mean);
    }

    #[test]
    fn reflections_stronger_than_the_real_echoes_are_found_too() {
        // Coated glass: reflects more than it transmits.
        let m = StrengthMixture::fit(&behind((2000.0, 2.9, 0.15), (8000.0, 3.4, 0.1))).unwrap();
        assert!((m.share - 0.8).abs() < 0.03, "{m:?}");
        assert!(m.reflected.mean > m.real.mean);
    }

    #[test]
    fn reflections_as_strong_as_the_real_echoes_give_no_mixture() {
        assert_eq!(
            StrengthMixture::fit(&behind((5000.0, 3.5, 0.2), (5000.0, 3.55, 0.2))),
            None
        );
    }

    #[test]
    fn too_few_confirmed_transmissions_give_no_mixture() {
        let mut b = behind((7000.0, 3.5, 0.2), (3000.0, 2.3, 0.25));
        b.transmitted = EchoHistogram::default();
        add_group(&mut b.transmitted, 150.0, 3.5, 0.2);
        assert!(b.transmitted.total() < MIN_TRANSMISSIONS);
        assert_eq!(StrengthMixture::fit(&b), None);
    }

    #[test]
    fn real_echoes_alone_give_a_small_share_or_none() {
        let b = behind((10000.0, 3.5, 0.2), (0.0, 2.3, 0.25));
        if let Some(m) = StrengthMixture::fit(&b) {
            assert!(m.share < 0.03, "{m:?}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]
        /// Groups a decade or more apart: the share comes back within a few
        /// per cent, whichever group is the stronger.
        #[test]
        fn separated_groups_give_back_their_share(
            share in 0.05f64..0.95,
            real_mean in 2.0f64..4.0,
            offset in prop_oneof![-2.0f64..-1.0, 1.0f64..1.5],
            real_spread in 0.1f64..0.3,
            reflected_spread in 0.1f64..0.3,
        ) {
            let n = 20000.0;
            let b = behind(
                ((1.0 - share) * n, real_mean, real_spread),
                (share * n, real_mean + offset, reflected_spread),
            );
            prop_assume!(b.transmitted.total() >= MIN_TRANSMISSIONS);
            let m = StrengthMixture::fit(&b).unwrap();
            prop_assert!((m.share - share).abs() < 0.04, "{:?} against {}", m, share);
            prop_assert!((0.0..=1.0).contains(&m.share));
        }
    }
}
