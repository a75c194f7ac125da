//! Reflection or transmission told by echo strength, learned per landmark.
//!
//! A return behind a pane either crossed it twice (transmitted: the power
//! is scaled by T², about 0.85 for plain glass near normal incidence) or was
//! reflected by it (R², about 0.006): through uncoated glass a reflection is
//! one to two orders of magnitude weaker than a transmitted echo from a
//! similar surface at the same range. Geometry cannot tell a floor behind
//! vertical glass from the reflection of the floor in front (the floor is
//! its own mirror image), but the echo strength can.
//!
//! No intensity scale is assumed. For each landmark the range-corrected
//! echo strengths `log10(I · r^k)` of the points behind it are split in two
//! by Otsu's method; the split is used only when the two groups are far
//! apart (coated glass with `R ≈ T` gives one group, and then this test
//! abstains), and the side that is transmission is read from anchors: points
//! whose mirror image lies in space seen free, which cannot be reflections.

use serde::{Deserialize, Serialize};

use crate::cloud::{Frame, IntensityScale};
use crate::sensor::OrganizedScan;

/// Histogram range and resolution of `log10(I · r^k)`.
const LOG_MIN: f64 = -1.0;
const LOG_MAX: f64 = 7.0;
const BIN: f64 = 0.05;
const BINS: usize = ((LOG_MAX - LOG_MIN) / BIN) as usize;

/// Settings of the per-landmark echo split: `[plane_map.echo_split]` sets
/// the range exponent and the separation; the rest are the method's
/// constants (see [`EchoSplitParams::default`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "EchoSplitKeys", into = "EchoSplitKeys")]
pub struct EchoSplitParams {
    /// Echo strength is corrected by the range to this power: `auto`
    /// takes it from what the frames' intensities measure (0 for a
    /// reflectivity, 2 for a raw power falling with the square of the
    /// range; [`IntensityScale`]), a number forces it.
    pub range_exponent: RangeExponent,
    /// Echo strength is corrected by the incidence on the surface hit
    /// (its normal from the neighbouring beams).
    pub incidence_correction: bool,
    /// The two groups' means must differ by this many decades.
    pub min_separation: f64,
    /// Anchors (points that cannot be reflections) needed to orient the
    /// split.
    pub min_anchors: u32,
    /// Share of the anchors that must fall on the transmitted side.
    pub min_anchor_agreement: f64,
    /// Points within this many decades of the threshold are left to the
    /// other tests.
    pub band: f64,
    /// Use a split only when its anchors (transmitted for sure) are the
    /// stronger group. Glass reflects a few per cent of the power and
    /// transmits most of it, so reflections are the weaker echoes; a split
    /// whose anchors fall on the weak side separates something else (dark
    /// and bright materials, near and far pane sides) and would call the
    /// bright real surfaces behind the glass reflections.
    pub reflection_is_weaker: bool,
    /// With fewer than `min_anchors` anchors, orient a split by physics
    /// alone when `reflection_is_weaker`: the weak group is the reflections
    /// (anchors that exist must still agree).
    pub orient_without_anchors: bool,
}

/// The keys of `[plane_map.echo_split]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EchoSplitKeys {
    /// The range exponent `k` of the echo strength log10(I r^k / cos):
    /// `auto` or a number.
    range_exponent: RangeExponent,
    /// The two groups' means must differ by this many decades.
    min_separation: f64,
}

impl From<EchoSplitKeys> for EchoSplitParams {
    fn from(k: EchoSplitKeys) -> Self {
        Self {
            range_exponent: k.range_exponent,
            min_separation: k.min_separation,
            ..Self::METHOD
        }
    }
}

impl From<EchoSplitParams> for EchoSplitKeys {
    fn from(p: EchoSplitParams) -> Self {
        Self {
            range_exponent: p.range_exponent,
            min_separation: p.min_separation,
        }
    }
}

impl EchoSplitParams {
    /// The split's method: strengths corrected by the incidence; at least
    /// 30 anchors, three quarters of them on the transmitted side, orient a
    /// split, and with none the weaker group is the reflections (glass
    /// reflects less than it transmits), a split whose anchors fall on the
    /// weak side being no split; points within 0.1 decades of the threshold
    /// are left to the other tests. `range_exponent` auto and
    /// `min_separation` 0.8 decades, as `configs/default.toml` sets them.
    pub const METHOD: Self = Self {
        range_exponent: RangeExponent::Auto(Auto::Auto),
        incidence_correction: true,
        min_separation: 0.8,
        min_anchors: 30,
        min_anchor_agreement: 0.75,
        band: 0.1,
        reflection_is_weaker: true,
        orient_without_anchors: true,
    };

    /// The `cos` of [`echo_strength`] for `frame`'s point `point` under
    /// these settings: the cosine of the incidence at which its beam met
    /// its surface (from its neighbours in `scan`) when strengths are
    /// corrected for it, else 1. Where the neighbours span no surface (a
    /// floor met at grazing incidence, whose next ring lies metres away)
    /// it is what `fallback` says (a caller that knows the surface, a floor
    /// or ceiling seen directly; asked only then), else 1. The strengths a
    /// split is fitted to are computed with it, as
    /// [`EchoSplit::incidence_cos`] computes the ones it decides.
    pub fn incidence_cos(
        &self,
        scan: &OrganizedScan,
        frame: &Frame,
        point: usize,
        fallback: impl FnOnce() -> Option<f64>,
    ) -> f64 {
        incidence_cos(self.incidence_correction, scan, frame, point, fallback)
    }
}

impl Default for EchoSplitParams {
    /// [`EchoSplitParams::METHOD`].
    fn default() -> Self {
        Self::METHOD
    }
}

/// The range exponent of the echo strength: from the intensities' scale,
/// or fixed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum RangeExponent {
    /// This power, whatever the intensities measure.
    Fixed(f64),
    /// `"auto"`: [`IntensityScale::range_exponent`] of the frames.
    Auto(Auto),
}

/// The word `auto` of [`RangeExponent::Auto`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Auto {
    /// From the intensities' scale.
    Auto,
}

impl RangeExponent {
    /// The exponent for intensities of `scale`.
    pub fn resolve(self, scale: IntensityScale) -> f64 {
        match self {
            RangeExponent::Fixed(k) => k,
            RangeExponent::Auto(_) => scale.range_exponent(),
        }
    }
}

/// Counts of echo strengths, `log10(I · r^k)` in fixed bins (bounded
/// memory whatever the number of frames).
#[derive(Debug, Clone, PartialEq)]
pub struct EchoHistogram {
    counts: Vec<u32>,
}

impl Default for EchoHistogram {
    fn default() -> Self {
        Self {
            counts: vec![0; BINS],
        }
    }
}

/// The `cos` of [`echo_strength`] for point `point` of `frame`: the cosine
/// of the incidence at which its beam met its surface (from its neighbours
/// in `scan`) when the strengths are corrected for it (`correct`), else 1;
/// where the neighbours do not span a surface, what `fallback` says (the
/// caller's knowledge of the surface, asked only then), else 1. One rule
/// for every strength, so that the strengths a split is fitted to and the
/// ones it decides are computed alike.
fn incidence_cos(
    correct: bool,
    scan: &OrganizedScan,
    frame: &Frame,
    point: usize,
    fallback: impl FnOnce() -> Option<f64>,
) -> f64 {
    if correct {
        scan.incidence_cos(frame, point)
            .or_else(fallback)
            .unwrap_or(1.0)
    } else {
        1.0
    }
}

/// The echo strength of a return of intensity `intensity` at `range` metres
/// from a surface met at incidence cosine `cos` (1 when unknown): a
/// Lambertian surface returns in proportion to `cos`, so dividing by it
/// leaves the reflectivity (floors met at grazing incidence far away are
/// not mistaken for weak reflections). The cosine is floored at 0.1.
#[inline]
pub fn echo_strength(intensity: f32, range: f64, range_exponent: f64, cos: f64) -> f64 {
    (intensity.max(0.5) as f64).log10() + range_exponent * range.max(1e-3).log10()
        - cos.clamp(0.1, 1.0).log10()
}

impl EchoHistogram {
    /// Each bin's centre strength (decades) and count, weakest first.
    pub fn bins(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .map(|(b, &c)| (centre(b), c as f64))
    }

    /// Count one echo strength.
    pub fn add(&mut self, strength: f64) {
        if strength.is_finite() {
            let b = ((strength - LOG_MIN) / BIN)
                .floor()
                .clamp(0.0, (BINS - 1) as f64);
            self.counts[b as usize] += 1;
        }
    }

    /// Add another histogram's counts.
    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
    }

    /// Echoes counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().map(|&c| c as u64).sum()
    }

    /// Echoes counted below `threshold` (by bin centre).
    pub fn below(&self, threshold: f64) -> u64 {
        self.total() - self.above(threshold)
    }

    /// The share of the echoes counted below `threshold` (0 when empty).
    pub fn share_below(&self, threshold: f64) -> f64 {
        match self.total() {
            0 => 0.0,
            n => self.below(threshold) as f64 / n as f64,
        }
    }

    /// The strength below which a share `q` of the echoes lies (bin
    /// centre); `None` when empty.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        let n = self.total();
        if n == 0 {
            return None;
        }
        let target = (q.clamp(0.0, 1.0) * n as f64).ceil().max(1.0) as u64;
        let mut seen = 0;
        for (b, &c) in self.counts.iter().enumerate() {
            seen += c as u64;
            if seen >= target {
                return Some(centre(b));
            }
        }
        Some(centre(BINS - 1))
    }

    /// The standard deviation of the strengths on one side of `threshold`
    /// (below it, or above it), decades; 0 when that side is empty.
    pub fn spread(&self, threshold: f64, below: bool) -> f64 {
        let (mut n, mut sum, mut sq) = (0.0, 0.0, 0.0);
        for (b, &c) in self.counts.iter().enumerate() {
            let x = centre(b);
            if (x < threshold) == below && c > 0 {
                let c = c as f64;
                n += c;
                sum += c * x;
                sq += c * x * x;
            }
        }
        if n == 0.0 {
            return 0.0;
        }
        let mean = sum / n;
        (sq / n - mean * mean).max(0.0).sqrt()
    }

    /// Echoes counted above `threshold`.
    fn above(&self, threshold: f64) -> u64 {
        self.counts
            .iter()
            .enumerate()
            .filter(|(b, _)| centre(*b) > threshold)
            .map(|(_, &c)| c as u64)
            .sum()
    }

    /// Otsu's threshold: the split maximising the between-group variance,
    /// with the two groups' means; `None` with fewer than two occupied bins.
    fn otsu(&self) -> Option<(f64, f64, f64)> {
        let total = self.total() as f64;
        let sum: f64 = self
            .counts
            .iter()
            .enumerate()
            .map(|(b, &c)| c as f64 * centre(b))
            .sum();
        let (mut w0, mut s0) = (0.0, 0.0);
        let mut best: Option<(f64, f64, f64, f64)> = None;
        for b in 0..BINS - 1 {
            w0 += self.counts[b] as f64;
            s0 += self.counts[b] as f64 * centre(b);
            let w1 = total - w0;
            if w0 == 0.0 || w1 == 0.0 {
                continue;
            }
            let (m0, m1) = (s0 / w0, (sum - s0) / w1);
            let between = w0 * w1 * (m0 - m1) * (m0 - m1);
            if best.is_none_or(|(v, ..)| between > v) {
                best = Some((between, centre(b) + BIN / 2.0, m0, m1));
            }
        }
        best.map(|(_, t, m0, m1)| (t, m0, m1))
    }
}

fn centre(bin: usize) -> f64 {
    LOG_MIN + (bin as f64 + 0.5) * BIN
}

/// A landmark's learned split between transmitted and reflected echoes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EchoSplit {
    /// Strength (`log10(I · r^k)`) between the two groups.
    pub threshold: f64,
    /// Half-width of the undecided band around the threshold, decades.
    pub band: f64,
    /// The range exponent `k` the strengths use.
    pub range_exponent: f64,
    /// Whether the strengths are corrected by the incidence on the surface.
    pub incidence_correction: bool,
    /// Whether the weaker group is the reflections (glass: `R < T`).
    pub weak_is_reflection: bool,
    /// Mean strength of the weaker group, decades.
    pub weak_mean: f64,
    /// Mean strength of the stronger group, decades.
    pub strong_mean: f64,
    /// Standard deviation of the weaker group, decades.
    pub weak_spread: f64,
    /// Standard deviation of the stronger group, decades.
    pub strong_spread: f64,
    /// Whether the groups are physics around the room's direct echoes, not
    /// fitted to this landmark's echoes: then only a weak echo is evidence
    /// (a strong one may be a transmission, or a reflection off coated
    /// glass, whose `R` is close to its `T`).
    pub from_physics: bool,
}

impl EchoSplit {
    /// Fit from the strengths of every point behind the landmark and of its
    /// anchors (points that cannot be reflections); `None` when the
    /// strengths do not fall in two groups far enough apart, or the anchors
    /// are too few or disagree.
    /// `range_exponent` is the one the strengths were computed with
    /// ([`RangeExponent::resolve`]).
    pub fn fit(
        all: &EchoHistogram,
        anchors: &EchoHistogram,
        p: &EchoSplitParams,
        range_exponent: f64,
    ) -> Option<Self> {
        let (threshold, m0, m1) = all.otsu()?;
        if (m1 - m0).abs() < p.min_separation {
            return None;
        }
        let n = anchors.total();
        let by_physics = p.orient_without_anchors && p.reflection_is_weaker;
        if n < p.min_anchors as u64 && !by_physics {
            return None;
        }
        let strong = if n < p.min_anchors as u64 {
            1.0
        } else {
            anchors.above(threshold) as f64 / n as f64
        };
        let weak_is_reflection = if strong >= p.min_anchor_agreement {
            true
        } else if 1.0 - strong >= p.min_anchor_agreement && !p.reflection_is_weaker {
            false
        } else {
            return None;
        };
        Some(Self {
            threshold,
            band: p.band,
            range_exponent,
            incidence_correction: p.incidence_correction,
            weak_is_reflection,
            weak_mean: m0.min(m1),
            strong_mean: m0.max(m1),
            weak_spread: all.spread(threshold, true),
            strong_spread: all.spread(threshold, false),
            from_physics: false,
        })
    }

    /// Whether a return of `intensity` at `range`, met at incidence cosine
    /// `cos`, was reflected (`Some(true)`), transmitted (`Some(false)`), or
    /// is too close to the threshold to say.
    pub fn reflected(&self, intensity: f32, range: f64, cos: f64) -> Option<bool> {
        let s = echo_strength(intensity, range, self.range_exponent, cos);
        if (s - self.threshold).abs() <= self.band {
            return None;
        }
        Some((s < self.threshold) == self.weak_is_reflection)
    }

    /// The `cos` of [`reflected`](Self::reflected) for `frame`'s point
    /// `point`: the cosine of the incidence at which its beam met its
    /// surface (from its neighbours in `scan`, else what `fallback`
    /// says of the surface) when this split's strengths are corrected
    /// for it, else 1, as [`EchoSplitParams::incidence_cos`] computed the
    /// strengths it was fitted to.
    pub fn incidence_cos(
        &self,
        scan: &OrganizedScan,
        frame: &Frame,
        point: usize,
        fallback: impl FnOnce() -> Option<f64>,
    ) -> f64 {
        incidence_cos(self.incidence_correction, scan, frame, point, fallback)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn histogram(values: impl IntoIterator<Item = f64>) -> EchoHistogram {
        let mut h = EchoHistogram::default();
        for v in values {
            h.add(v);
        }
        h
    }

    /// Two groups 1.5 decades apart split between them, oriented by the
    /// anchors; one group (coated glass) gives no split.
    #[test]
    fn two_groups_split_and_one_group_does_not() {
        let mut rng = crate::rng::SplitMix64::new(5);
        let weak: Vec<f64> = (0..500).map(|_| 2.0 + 0.3 * rng.unit()).collect();
        let strong: Vec<f64> = (0..800).map(|_| 3.5 + 0.4 * rng.unit()).collect();
        let all = histogram(weak.iter().chain(&strong).copied());
        let anchors = histogram(strong.iter().take(100).copied());
        let p = EchoSplitParams {
            incidence_correction: false,
            reflection_is_weaker: false,
            orient_without_anchors: false,
            ..EchoSplitParams::default()
        };
        let split = EchoSplit::fit(&all, &anchors, &p, 2.0).expect("a split");
        assert!(split.threshold > 2.3 && split.threshold < 3.5, "{split:?}");
        assert!(split.weak_is_reflection);
        // A weak echo at 10 m is a reflection, a strong one transmitted.
        assert_eq!(split.reflected(1.0, 10.0, 1.0), Some(true));
        assert_eq!(split.reflected(100.0, 10.0, 1.0), Some(false));
        // A weak echo from a surface met at grazing incidence is not.
        assert_eq!(split.reflected(5.0, 10.0, 0.1), Some(false));
        // Anchors on the weak side flip the orientation (strong mirrors)...
        let weak_anchors = histogram(weak.iter().take(100).copied());
        let flipped = EchoSplit::fit(&all, &weak_anchors, &p, 2.0);
        assert!(!flipped.expect("a split").weak_is_reflection);
        // ... unless reflections must be the weaker echoes (glass that
        // transmits more than it reflects): then the split separates
        // something else and is not used.
        let glass = EchoSplitParams {
            reflection_is_weaker: true,
            ..p
        };
        assert!(EchoSplit::fit(&all, &weak_anchors, &glass, 2.0).is_none());
        assert!(
            EchoSplit::fit(&all, &anchors, &glass, 2.0)
                .expect("a split")
                .weak_is_reflection
        );
        // Too few anchors, or anchors on both sides: no split.
        assert!(
            EchoSplit::fit(&all, &histogram(strong.iter().take(5).copied()), &p, 2.0).is_none()
        );
        let mixed = histogram(weak.iter().take(50).chain(strong.iter().take(50)).copied());
        assert!(EchoSplit::fit(&all, &mixed, &p, 2.0).is_none());
        // One group: no split.
        let one = histogram(strong.iter().copied());
        assert!(EchoSplit::fit(&one, &anchors, &p, 2.0).is_none());
    }

    /// Glass behind which the scene is its own mirror image (a door across
    /// a corridor) has no anchors at all: its two echo groups orient by
    /// physics (reflections weaker) when switched on.
    #[test]
    fn without_anchors_two_groups_are_oriented_by_physics() {
        let mut rng = crate::rng::SplitMix64::new(7);
        let weak: Vec<f64> = (0..600).map(|_| 2.0 + 0.3 * rng.unit()).collect();
        let strong: Vec<f64> = (0..900).map(|_| 3.5 + 0.4 * rng.unit()).collect();
        let two = histogram(weak.iter().chain(&strong).copied());
        let none = EchoHistogram::default();
        let old = EchoSplitParams {
            reflection_is_weaker: true,
            orient_without_anchors: false,
            ..EchoSplitParams::default()
        };
        let new = EchoSplitParams {
            orient_without_anchors: true,
            ..old
        };
        assert_eq!(EchoSplit::fit(&two, &none, &old, 2.0), None);
        let split = EchoSplit::fit(&two, &none, &new, 2.0).expect("a split by physics");
        assert!(split.weak_is_reflection);
        // Anchors that exist must still agree.
        let weak_anchors = histogram(weak.iter().take(100).copied());
        assert_eq!(EchoSplit::fit(&two, &weak_anchors, &new, 2.0), None);
    }

    /// A floor far off is met at grazing incidence: its next ring lies
    /// metres away, the scan's neighbours span no surface, and the cosine
    /// the caller knows (the floor is horizontal) is used instead of 1;
    /// without the incidence correction it is 1 whatever the caller knows.
    #[test]
    fn a_grazing_floor_takes_the_callers_incidence() {
        use crate::sensor::scan::surface_frame;
        use crate::sensor::SensorModel;
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        // The floor 1 m below the sensor, out to 20 m.
        let frame = surface_frame(&sensor, "floor", |d| {
            (d.z <= -0.02).then(|| d * (-1.0 / d.z))
        });
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let corrected = EchoSplitParams::default();
        let uncorrected = EchoSplitParams {
            incidence_correction: false,
            ..corrected
        };
        let mut grazing = 0;
        for (i, pt) in frame.points.iter().enumerate() {
            let p = pt.position();
            let truth = 1.0 / p.coords.norm();
            if scan.incidence_cos(&frame, i).is_some() {
                // Where the neighbours tell, they decide.
                let own = corrected.incidence_cos(&scan, &frame, i, || None);
                assert_eq!(corrected.incidence_cos(&scan, &frame, i, || Some(0.5)), own);
                continue;
            }
            grazing += 1;
            assert_eq!(corrected.incidence_cos(&scan, &frame, i, || None), 1.0);
            let cos = corrected.incidence_cos(&scan, &frame, i, || Some(truth));
            assert!((cos - truth).abs() < 1e-12, "point {i}: {cos} vs {truth}");
            assert_eq!(
                uncorrected.incidence_cos(&scan, &frame, i, || Some(truth)),
                1.0
            );
        }
        // The far floor is where the neighbours fail.
        assert!(grazing > 100, "{grazing}");
    }

    /// `auto` follows the intensities' scale, a number forces the
    /// exponent; anything else is refused.
    #[test]
    fn range_exponent_is_auto_or_a_number() {
        #[derive(Deserialize)]
        struct Key {
            k: RangeExponent,
        }
        let parse = |text: &str| toml::from_str::<Key>(text).map(|key| key.k);
        let auto = parse("k = \"auto\"").unwrap();
        assert_eq!(auto.resolve(IntensityScale::Reflectivity), 0.0);
        assert_eq!(auto.resolve(IntensityScale::RawPower), 2.0);
        let fixed = parse("k = 1.5").unwrap();
        assert_eq!(fixed.resolve(IntensityScale::Reflectivity), 1.5);
        assert_eq!(fixed.resolve(IntensityScale::RawPower), 1.5);
        assert!(parse("k = \"sensor\"").is_err());
        assert_eq!(EchoSplitParams::default().range_exponent, auto);
    }
}
