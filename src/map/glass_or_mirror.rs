//! Glass or mirror, per landmark, as a probability from all of its echoes
//! over the sequence, and the split of its echoes into reflected and
//! transmitted ones ([`EchoSplit`]).
//!
//! Two observations, each weighed as a binomial count against what a
//! mirror predicts (a glass landmark may show any share):
//! - **transmissions confirmed by space seen directly**: points behind it
//!   whose mirror image the seen space refutes are real, seen through it. A
//!   mirror transmits nothing: only pose and plane errors give such points,
//!   at a rate of `false_transmission_rate`.
//! - **weak echoes**: glass reflects a few per cent (`R²` about 0.01 of the
//!   power), so its reflections come back a decade or more weaker than
//!   direct echoes from the same surfaces; a mirror reflects most of the
//!   light (`R² > 0.6`), and its images are as strong as the room. The share
//!   of echoes behind it weaker than the room's typical direct echo by
//!   `weak_decades` is, behind a mirror, the share of the room's direct
//!   echoes that weak.
//!
//! Points of one landmark are not independent (one pose error moves them
//! all): each count weighs as `effective_views` observations at most.

use serde::{Deserialize, Serialize};

use super::reflection_share::StrengthMixture;
use crate::reflect::{more_likely_mirror, EchoHistogram, EchoSplit, EchoSplitParams};

/// Parameters of the glass-or-mirror estimate (`[plane_map.mirror]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MirrorParams {
    /// Probability that a reflective landmark is a mirror before its
    /// evidence.
    pub prior: f64,
    /// Share of the points behind a mirror that the seen space calls real
    /// all the same (pose and plane errors, beams passing its edge).
    pub false_transmission_rate: f64,
    /// Independent observations a landmark's counts weigh as at most.
    pub effective_views: f64,
    /// A glass reflection is at least this much weaker than a direct echo
    /// from the same surface, decades (`R²` of 0.1 or less).
    pub weak_decades: f64,
    /// A reflection off plain glass is this much weaker than a direct echo
    /// from the same surface, decades (`R²` of 0.01-0.1 at the incidences
    /// glass echoes at): where the echoes behind a landmark do not fall in
    /// two groups (all transmitted, or all reflected), its split is this
    /// physics around the room's direct echoes.
    pub glass_reflection_decades: f64,
}

/// The values of `configs/default.toml`.
impl Default for MirrorParams {
    fn default() -> Self {
        crate::config::default_section("plane_map.mirror")
    }
}

/// The echoes behind one landmark over the keyframes (integer counts: the
/// sum does not depend on the order or the threads).
#[derive(Debug, Clone, Default)]
pub struct BehindEchoes {
    /// The strengths of every point behind it (its echo split).
    pub all: EchoHistogram,
    /// ... of those transmitted for sure (the split's orientation).
    pub anchors: EchoHistogram,
    /// ... of those whose beam crossed it well inside its extent.
    pub inside: EchoHistogram,
    /// ... of those of `inside` that the seen space calls real where
    /// measured (confirmed transmissions).
    pub transmitted: EchoHistogram,
    /// How many of `inside` have a mirror image on a surface seen directly
    /// and none where they were measured (confirmed reflections).
    pub imaged: u64,
    /// How many images of `inside`'s echoes, moved off the mirror position
    /// along the plane's normal ([`IMAGE_NULL_SHIFTS`]), land the same way,
    /// summed over the shifts: the chance landings that `imaged` also
    /// holds (a real echo's image lands on a seen surface as often moved
    /// or not; a reflection's, moved off the surface it came from, rarely).
    pub imaged_by_chance: u64,
    /// Of the confirmed transmissions, how many ended at each level (floor
    /// or ceiling) seen directly, by the level's index.
    pub transmitted_at_level: Vec<u64>,
    /// One frame's confirmed transmissions, as beams behind the pane (what
    /// a transmitted beam crossed is empty): carved into the space seen
    /// through glass frame by frame, not summed ([`BehindEchoes::merge`]
    /// leaves them).
    pub through: Vec<ThroughBeam>,
    /// One frame's echoes inside, where they landed (world frame) and how
    /// strong they were: once the landmark's split is known, the ones on
    /// its transmitted side are surfaces seen through the glass. Per frame,
    /// like `through`.
    pub landed: Vec<LandedEcho>,
}

/// An echo behind a landmark: where it landed (world frame) and its
/// strength (`log10(I r^k / cos)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandedEcho {
    /// Where it was measured, world frame.
    pub position: [f32; 3],
    /// Its echo strength, decades.
    pub strength: f32,
}

/// A confirmed transmission's beam behind its pane, world frame: from where
/// it crossed the pane to where it ended, and the echo's range from the
/// sensor (a beam stops short of its end in proportion, as direct ones do).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThroughBeam {
    /// Where the beam crossed the pane.
    pub start: [f32; 3],
    /// Where it ended (the echo).
    pub end: [f32; 3],
    /// The echo's range, m.
    pub range: f32,
}

impl BehindEchoes {
    /// Add another frame's counts.
    pub fn merge(&mut self, other: &Self) {
        self.all.merge(&other.all);
        self.anchors.merge(&other.anchors);
        self.inside.merge(&other.inside);
        self.transmitted.merge(&other.transmitted);
        self.imaged += other.imaged;
        self.imaged_by_chance += other.imaged_by_chance;
        for (k, &n) in other.transmitted_at_level.iter().enumerate() {
            *self.at_level(k) += n;
        }
    }

    /// The count of confirmed transmissions that ended at level `k`, the
    /// list grown to hold it.
    pub fn at_level(&mut self, k: usize) -> &mut u64 {
        if self.transmitted_at_level.len() <= k {
            self.transmitted_at_level.resize(k + 1, 0);
        }
        &mut self.transmitted_at_level[k]
    }

    /// The heights among `levels` that run on behind the landmark: at
    /// least [`MIN_LEVEL_TRANSMISSIONS`] confirmed transmissions, and
    /// [`LEVEL_TRANSMISSION_SHARE`] of them, ended at each.
    pub fn levels_behind(&self, levels: &[f64]) -> Vec<f64> {
        levels
            .iter()
            .zip(&self.transmitted_at_level)
            .filter(|(_, &n)| {
                n >= MIN_LEVEL_TRANSMISSIONS
                    && n as f64 >= LEVEL_TRANSMISSION_SHARE * self.transmitted.total() as f64
            })
            .map(|(&h, _)| h)
            .collect()
    }
}

/// A floor or ceiling runs on behind a landmark when at least this many
/// confirmed transmissions over the keyframes ended at its height: a few
/// stray ones (a pose error at the pane's foot) do not make a floor.
pub const MIN_LEVEL_TRANSMISSIONS: u64 = 20;

/// ... and at least this share of all its confirmed transmissions: a floor
/// seen through the glass takes a large share of them, a facade beyond it
/// that crosses the level's height a thin band.
pub const LEVEL_TRANSMISSION_SHARE: f64 = 0.1;

/// What the sequence says about one landmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlassOrMirror {
    /// Its echoes' split into reflected and transmitted, when they fall in
    /// two groups.
    pub echo_split: Option<EchoSplit>,
    /// P(mirror | its echoes).
    pub mirror_probability: f64,
    /// The log-likelihood ratio (mirror against glass) of the confirmed
    /// transmissions.
    pub transmission_llr: f64,
    /// ... of the weak echoes.
    pub weak_echo_llr: f64,
    /// The share of reflections among its echoes, where their strengths
    /// tell it ([`StrengthMixture`]).
    pub reflection_share: Option<f64>,
    /// The share of reflections among the echoes the seen space decides
    /// ([`decided_share`]).
    pub decided_share: Option<f64>,
}

impl GlassOrMirror {
    /// Whether the landmark is more likely a mirror than glass
    /// ([`more_likely_mirror`], as [`BoundedPlane::is_mirror`](crate::reflect::BoundedPlane::is_mirror)).
    pub fn is_mirror(&self) -> bool {
        more_likely_mirror(self.mirror_probability)
    }
}

/// The estimate for a landmark with echoes `behind`, given the strengths of
/// the sequence's direct echoes `direct` and the range exponent the
/// strengths use.
pub fn glass_or_mirror(
    behind: &BehindEchoes,
    direct: &EchoHistogram,
    split: &EchoSplitParams,
    p: &MirrorParams,
    range_exponent: f64,
) -> GlassOrMirror {
    let echo_split = EchoSplit::fit(&behind.all, &behind.anchors, split, range_exponent)
        .or_else(|| physical_split(direct, split, p, range_exponent));
    let n = behind.inside.total();
    let transmission_llr = binomial_llr(
        behind.transmitted.total() as f64,
        n as f64,
        p.false_transmission_rate,
        p.effective_views,
    );
    let weak_echo_llr = match direct.quantile(0.5) {
        Some(typical) if direct.total() > 0 => {
            let threshold = typical - p.weak_decades;
            let weak = behind.inside.below(threshold) as f64;
            let expected = direct.share_below(threshold).max(1e-3);
            binomial_llr(weak, n as f64, expected, p.effective_views)
        }
        _ => 0.0,
    };
    let prior = p.prior.clamp(1e-3, 1.0 - 1e-3);
    let log_odds = (prior / (1.0 - prior)).ln() + transmission_llr + weak_echo_llr;
    GlassOrMirror {
        echo_split,
        mirror_probability: 1.0 / (1.0 + (-log_odds).exp()),
        transmission_llr,
        weak_echo_llr,
        reflection_share: StrengthMixture::fit(behind).map(|m| m.share),
        decided_share: decided_share(behind),
    }
}

/// The split physics predicts around the room's direct echoes `direct`:
/// transmitted echoes as strong as direct ones (`T²` near 1), reflections
/// `glass_reflection_decades` weaker, both with the direct echoes' spread.
/// `None` with fewer than [`MIN_DIRECT`] direct echoes.
fn physical_split(
    direct: &EchoHistogram,
    split: &EchoSplitParams,
    p: &MirrorParams,
    range_exponent: f64,
) -> Option<EchoSplit> {
    if direct.total() < MIN_DIRECT {
        return None;
    }
    let typical = direct.quantile(0.5)?;
    let spread = direct.spread(f64::INFINITY, true);
    let weak_mean = typical - p.glass_reflection_decades;

    Some(EchoSplit {
        threshold: 0.5 * (weak_mean + typical),
        band: split.band,
        range_exponent,
        incidence_correction: split.incidence_correction,
        weak_is_reflection: true,
        weak_mean,
        strong_mean: typical,
        weak_spread: spread,
        strong_spread: spread,
        from_physics: true,
    })
}

/// The share of reflections among a landmark's echoes from those the seen
/// space decides: confirmed reflections against confirmed transmissions
/// (each beam's image or position seen or not is taken as independent of
/// what it is), with one of each assumed before; `None` with fewer than
/// [`MIN_DECIDED`] decided. The confirmed reflections are the images on a
/// seen surface beyond those that land there by chance: as many as land
/// there when moved off the mirror position ([`IMAGE_NULL_SHIFTS`]). In a
/// furnished hall behind a clear pane, a real echo's image lands on a
/// surface a quarter of the time, and those landings outnumbered the
/// pane's few reflections ten to one.
pub fn decided_share(behind: &BehindEchoes) -> Option<f64> {
    let chance = behind.imaged_by_chance as f64 / IMAGE_NULL_SHIFTS.len() as f64;
    let r = (behind.imaged as f64 - chance).max(0.0);
    let t = behind.transmitted.total() as f64;
    (r + t >= MIN_DECIDED as f64).then(|| (r + 1.0) / (r + t + 2.0))
}

/// How far the images of the chance-landing count
/// ([`BehindEchoes::imaged_by_chance`]) are moved along the landmark's
/// normal, m, away from the pane and towards it: farther than a seen
/// surface's support radius (0.32 m) and the pose and plane errors, so a
/// reflection's image leaves the surface it came from, and less than a
/// room, so a real echo's image samples the same room.
pub const IMAGE_NULL_SHIFTS: [f64; 2] = [1.0, -1.0];

/// Decided echoes needed for [`decided_share`].
pub const MIN_DECIDED: u64 = 100;

/// Direct echoes needed to know the room's echo strengths.
const MIN_DIRECT: u64 = 1000;

/// `ln P(k of n | rate q) / P(k of n | any rate)`, the counts scaled down to
/// at most `views` observations: positive where `k / n` is what rate `q`
/// predicts, negative where it is far above it. Under "any rate" (uniform)
/// every count has probability `1 / (n + 1)`.
pub fn binomial_llr(k: f64, n: f64, q: f64, views: f64) -> f64 {
    if !(n > 0.0) {
        return 0.0;
    }
    let scale = (views / n).min(1.0);
    let (k, n) = (k * scale, n * scale);
    let q = q.clamp(1e-6, 1.0 - 1e-6);
    ln_choose(n, k) + k * q.ln() + (n - k) * (1.0 - q).ln() + (n + 1.0).ln()
}

/// `ln C(n, k)` for real `n >= k >= 0`.
fn ln_choose(n: f64, k: f64) -> f64 {
    ln_gamma(n + 1.0) - ln_gamma(k + 1.0) - ln_gamma(n - k + 1.0)
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7; relative error below 1e-13).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn histogram(values: impl IntoIterator<Item = f64>) -> EchoHistogram {
        let mut h = EchoHistogram::default();
        for v in values {
            h.add(v);
        }
        h
    }

    proptest! {
        /// ln Γ satisfies Γ(x + 1) = x Γ(x).
        #[test]
        fn ln_gamma_recurrence(x in 0.01f64..200.0) {
            let lhs = ln_gamma(x + 1.0);
            let rhs = x.ln() + ln_gamma(x);
            prop_assert!((lhs - rhs).abs() < 1e-9 * (1.0 + lhs.abs()), "{lhs} {rhs}");
        }
    }

    #[test]
    fn ln_gamma_of_integers_is_ln_factorial() {
        let mut f = 1.0f64;
        for n in 1..20 {
            f *= n as f64;
            assert!((ln_gamma(n as f64 + 1.0) - f.ln()).abs() < 1e-10);
        }
    }

    /// A count at the mirror's rate favours the mirror, one far above it
    /// favours glass, and more views weigh more, up to the cap.
    #[test]
    fn binomial_counts_weigh_towards_the_rate_they_fit() {
        assert!(binomial_llr(0.0, 1000.0, 0.005, 50.0) > 2.0);
        assert!(binomial_llr(300.0, 1000.0, 0.005, 50.0) < -20.0);
        assert!(binomial_llr(0.0, 20.0, 0.005, 50.0) < binomial_llr(0.0, 40.0, 0.005, 50.0));
        assert_eq!(
            binomial_llr(0.0, 1e6, 0.005, 50.0),
            binomial_llr(0.0, 50.0, 0.005, 50.0)
        );
        assert_eq!(binomial_llr(0.0, 0.0, 0.005, 50.0), 0.0);
    }

    /// Behind a mirror the echoes are as strong as the room and none are
    /// confirmed transmitted: a mirror. Behind glass many are a decade
    /// weaker, or many are confirmed transmitted: glass.
    #[test]
    fn mirrors_and_glass_are_told_apart_by_their_echoes() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let room: Vec<f64> = (0..4000).map(|_| 3.0 + 0.8 * rng.unit()).collect();
        let direct = histogram(room.iter().copied());
        let split = EchoSplitParams::default();
        let p = MirrorParams::default();
        let mirror_like = histogram(room.iter().map(|s| s - 0.1));
        let mirror = BehindEchoes {
            all: mirror_like.clone(),
            inside: mirror_like,
            ..BehindEchoes::default()
        };
        let m = glass_or_mirror(&mirror, &direct, &split, &p, 2.0);
        assert!(m.mirror_probability > 0.9, "{m:?}");
        let glass_like =
            histogram(
                room.iter()
                    .enumerate()
                    .map(|(i, s)| if i % 2 == 0 { s - 2.0 } else { s - 0.1 }),
            );
        let glass = BehindEchoes {
            all: glass_like.clone(),
            inside: glass_like,
            ..BehindEchoes::default()
        };
        let g = glass_or_mirror(&glass, &direct, &split, &p, 2.0);
        assert!(g.mirror_probability < 0.1, "{g:?}");
        let seen_through = BehindEchoes {
            transmitted: transmissions(400),
            ..mirror
        };
        let t = glass_or_mirror(&seen_through, &direct, &split, &p, 2.0);
        assert!(t.mirror_probability < 0.1, "{t:?}");
    }

    /// Without a strength mixture, the share of reflections is that of the
    /// echoes the seen space decided: confirmed reflections against
    /// confirmed transmissions; too few decided give none.
    #[test]
    fn the_share_of_reflections_follows_the_decided_echoes() {
        let direct = histogram((0..2000).map(|i| 3.0 + 0.0004 * i as f64));
        let (split, p) = (EchoSplitParams::default(), MirrorParams::default());
        let share = |imaged: u64, transmitted: usize| {
            let behind = BehindEchoes {
                transmitted: transmissions(transmitted),
                imaged,
                ..BehindEchoes::default()
            };
            glass_or_mirror(&behind, &direct, &split, &p, 2.0).decided_share
        };
        let mostly_real = share(8, 392).expect("400 decided");
        assert!((mostly_real - 9.0 / 402.0).abs() < 1e-12, "{mostly_real}");
        let mostly_reflected = share(300, 100).expect("400 decided");
        assert!(mostly_reflected > 0.7, "{mostly_reflected}");
        assert_eq!(share(10, 40), None);
    }

    /// Images that land on a seen surface only as often as images moved
    /// off the mirror position are chance landings, not reflections: behind
    /// a clear pane in a furnished hall they would otherwise outnumber its
    /// few reflections.
    #[test]
    fn chance_landings_are_no_confirmed_reflections() {
        let direct = histogram((0..2000).map(|i| 3.0 + 0.0004 * i as f64));
        let (split, p) = (EchoSplitParams::default(), MirrorParams::default());
        let share = |imaged: u64, by_chance_per_shift: u64, transmitted: usize| {
            let behind = BehindEchoes {
                transmitted: transmissions(transmitted),
                imaged,
                imaged_by_chance: by_chance_per_shift * IMAGE_NULL_SHIFTS.len() as u64,
                ..BehindEchoes::default()
            };
            glass_or_mirror(&behind, &direct, &split, &p, 2.0).decided_share
        };
        // 500 images on surfaces, 450 of them as often moved: 50 reflections.
        let clear = share(500, 450, 400).expect("450 decided");
        assert!((clear - 51.0 / 452.0).abs() < 1e-12, "{clear}");
        assert!(share(500, 0, 400).unwrap() > 0.5);
        // More chance landings than images: no reflection confirmed, and
        // too few decided without them.
        assert!((share(300, 400, 400).unwrap() - 1.0 / 402.0).abs() < 1e-12);
        assert_eq!(share(300, 300, 60), None);
    }

    /// `n` confirmed transmissions, all of one strength.
    fn transmissions(n: usize) -> EchoHistogram {
        histogram(std::iter::repeat_n(3.0, n))
    }

    /// A level runs on behind a landmark when enough of its confirmed
    /// transmissions, and a large enough share of them, ended there; counts
    /// merged over frames add up level by level.
    #[test]
    fn a_level_runs_on_behind_where_transmissions_end_at_it() {
        let mut a = BehindEchoes {
            transmitted: transmissions(100),
            transmitted_at_level: vec![30],
            ..BehindEchoes::default()
        };
        let b = BehindEchoes {
            transmitted: transmissions(100),
            transmitted_at_level: vec![0, 5],
            ..BehindEchoes::default()
        };
        a.merge(&b);
        assert_eq!(a.transmitted.total(), 200);
        assert_eq!(a.transmitted_at_level, vec![30, 5]);
        // 30 of 200 (15 %) at the floor, 5 at the ceiling (too few).
        assert_eq!(a.levels_behind(&[0.0, 3.0]), vec![0.0]);
        a.transmitted = transmissions(1000); // 3 %: a band of a facade.
        assert!(a.levels_behind(&[0.0, 3.0]).is_empty());
    }
}
