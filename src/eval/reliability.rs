//! Calibration of the per-point confidence: a reliability diagram's counts.
//!
//! A classifier says, per point, the probability that the class it gave is
//! right (`FrameOutput::confidence`, the `.prob` files). Whether those
//! probabilities mean what they say is measured here: the points are
//! binned by predicted confidence ([`BINS`] bins of 0.1), and per bin the
//! share actually correct is compared with the mean confidence. A
//! calibrated classifier's points lie on the diagonal.
//!
//! Which points count, and when one is correct, follow the scoring of
//! [`Confusion`](super::Confusion) exactly ([`truth_class`]): only points
//! with a scored truth label (1, 2, 3, 5, 6; labels 0 and 4 are ignored)
//! and a prediction other than unclassified are binned, and a point is
//! correct when its predicted class is its truth's scored class (glass
//! and mirror, labels 2 and 3, are both the reflective-surface class 2).

use serde::{Deserialize, Serialize};

use super::metrics::truth_class;
use crate::classify::Class;

/// Bins of predicted confidence, each 0.1 wide: bin `k` holds confidences
/// in `[k/10, (k+1)/10)`, the last one `[0.9, 1]`.
pub const BINS: usize = 10;

/// The confidence from which a point counts as confident in
/// [`ReliabilityReport::confident_accuracy`].
pub const CONFIDENT: f32 = 0.9;

/// Counts of one bin.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BinCounts {
    /// Points in the bin.
    pub points: u64,
    /// Of them, the points predicted as their truth's class.
    pub correct: u64,
    /// The sum of their confidences.
    pub confidence_sum: f64,
}

/// The reliability accumulator: per bin of predicted confidence, how many
/// points and how many of them correct. Add frames with
/// [`add`](Self::add), combine runs with [`merge`](Self::merge), read the
/// figures with [`report`](Self::report).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Reliability {
    /// One per bin, in order of confidence.
    pub bins: [BinCounts; BINS],
    /// Binned points with confidence at least [`CONFIDENT`].
    pub confident: u64,
    /// Of them, the points correct.
    pub confident_correct: u64,
}

/// The bin of confidence `c` (in `[0, 1]`); computed in `f32`, so the
/// written decimal thresholds fall where they read (0.9 is in the last
/// bin, as it is confident).
fn bin_of(c: f32) -> usize {
    ((c * BINS as f32).floor().max(0.0) as usize).min(BINS - 1)
}

impl Reliability {
    /// Add one point: its truth `label` (3DRef id), predicted `class` and
    /// the `confidence` of that class. Points without a scored label, left
    /// unclassified, or whose confidence is not a number in `[0, 1]`, are
    /// not binned.
    pub fn add_point(&mut self, label: u8, class: Class, confidence: f32) {
        if class == Class::Unclassified || !(0.0..=1.0).contains(&confidence) {
            return;
        }
        let Some(truth) = truth_class(label) else {
            return;
        };
        let correct = truth == class;
        let bin = &mut self.bins[bin_of(confidence)];
        bin.points += 1;
        bin.correct += correct as u64;
        bin.confidence_sum += confidence as f64;
        if confidence >= CONFIDENT {
            self.confident += 1;
            self.confident_correct += correct as u64;
        }
    }

    /// Add one frame's labels, predictions and confidences (same order;
    /// the shortest of the three bounds what is added).
    pub fn add(&mut self, labels: &[u8], classes: &[Class], confidence: &[f32]) {
        self.add_points(
            labels
                .iter()
                .zip(classes)
                .zip(confidence)
                .map(|((&l, &c), &p)| (l, c, p)),
        );
    }

    /// Add (label, prediction, confidence) triples.
    pub fn add_points(&mut self, points: impl IntoIterator<Item = (u8, Class, f32)>) {
        // Most points are certain (the beam test's classes): counted here and
        // binned together.
        let (mut certain, mut certain_correct) = (0u64, 0u64);
        for (l, c, p) in points {
            if p == 1.0 && c != Class::Unclassified {
                if let Some(truth) = truth_class(l) {
                    certain += 1;
                    certain_correct += u64::from(truth == c);
                }
                continue;
            }
            self.add_point(l, c, p);
        }
        let bin = &mut self.bins[bin_of(1.0)];
        bin.points += certain;
        bin.correct += certain_correct;
        bin.confidence_sum += certain as f64;
        if 1.0 >= CONFIDENT {
            self.confident += certain;
            self.confident_correct += certain_correct;
        }
    }

    /// Merge another accumulator into this one.
    pub fn merge(&mut self, other: &Reliability) {
        for (a, b) in self.bins.iter_mut().zip(&other.bins) {
            a.points += b.points;
            a.correct += b.correct;
            a.confidence_sum += b.confidence_sum;
        }
        self.confident += other.confident;
        self.confident_correct += other.confident_correct;
    }

    /// Points binned.
    pub fn points(&self) -> u64 {
        self.bins.iter().map(|b| b.points).sum()
    }

    /// The figures: per bin the mean confidence and the share correct, the
    /// expected calibration error and the accuracy of the confident points.
    pub fn report(&self) -> ReliabilityReport {
        let ratio = |num: f64, den: u64| {
            if den == 0 {
                f64::NAN
            } else {
                num / den as f64
            }
        };
        let points = self.points();
        let bins: Vec<ReliabilityBin> = self
            .bins
            .iter()
            .enumerate()
            .map(|(k, b)| ReliabilityBin {
                lower: k as f64 / BINS as f64,
                upper: (k + 1) as f64 / BINS as f64,
                points: b.points,
                correct: b.correct,
                mean_confidence: ratio(b.confidence_sum, b.points),
                accuracy: ratio(b.correct as f64, b.points),
            })
            .collect();
        let ece = if points == 0 {
            f64::NAN
        } else {
            bins.iter()
                .filter(|b| b.points > 0)
                .map(|b| b.points as f64 / points as f64 * (b.accuracy - b.mean_confidence).abs())
                .sum()
        };
        let correct: u64 = self.bins.iter().map(|b| b.correct).sum();
        ReliabilityReport {
            bins,
            points,
            accuracy: ratio(correct as f64, points),
            mean_confidence: ratio(self.bins.iter().map(|b| b.confidence_sum).sum(), points),
            ece,
            confident_points: self.confident,
            confident_accuracy: ratio(self.confident_correct as f64, self.confident),
        }
    }
}

/// One bin of a [`ReliabilityReport`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReliabilityBin {
    /// Lowest confidence of the bin.
    pub lower: f64,
    /// Upper end of the bin (excluded, but for the last bin's 1).
    pub upper: f64,
    /// Points in the bin.
    pub points: u64,
    /// Of them, the points correct.
    pub correct: u64,
    /// Their mean predicted confidence (NaN, `null` in JSON, when empty).
    pub mean_confidence: f64,
    /// The share of them correct, in `[0, 1]` (NaN when empty).
    pub accuracy: f64,
}

/// The reliability figures, probabilities in `[0, 1]` (not percent, so
/// they compare with the confidences directly).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReliabilityReport {
    /// [`BINS`] bins in order of confidence.
    pub bins: Vec<ReliabilityBin>,
    /// Points binned (scored label, prediction other than unclassified).
    pub points: u64,
    /// Share of them correct.
    pub accuracy: f64,
    /// Their mean confidence.
    pub mean_confidence: f64,
    /// Expected calibration error: the mean over bins, weighted by points,
    /// of |share correct − mean confidence| (NaN without points).
    pub ece: f64,
    /// Points with confidence at least [`CONFIDENT`] (0.9).
    pub confident_points: u64,
    /// Share of them correct (NaN when none).
    pub confident_accuracy: f64,
}

impl ReliabilityReport {
    /// A Markdown table: bin, points, mean predicted confidence, measured
    /// accuracy; then the calibration error and the confident points.
    pub fn markdown(&self) -> String {
        let f = |v: f64| {
            if v.is_finite() {
                format!("{v:.3}")
            } else {
                "–".into()
            }
        };
        let mut s = String::from(
            "| confidence | points | predicted (mean) | measured accuracy |\n|---|---:|---:|---:|\n",
        );
        for (k, b) in self.bins.iter().enumerate() {
            let close = if k + 1 == self.bins.len() { ']' } else { ')' };
            s.push_str(&format!(
                "| [{:.1}, {:.1}{close} | {} | {} | {} |\n",
                b.lower,
                b.upper,
                b.points,
                f(b.mean_confidence),
                f(b.accuracy)
            ));
        }
        s.push_str(&format!(
            "\n{} points; accuracy {}, mean confidence {}, expected calibration error {}.\nConfidence >= {CONFIDENT}: {} points, {} of them correct.\n",
            self.points,
            f(self.accuracy),
            f(self.mean_confidence),
            f(self.ece),
            self.confident_points,
            if self.confident_accuracy.is_finite() {
                format!("{:.1}%", 100.0 * self.confident_accuracy)
            } else {
                "–".into()
            }
        ));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-6
    }

    /// The certain points' shortcut bins as one point at a time does,
    /// certain unclassified points and ignored labels included.
    #[test]
    fn certain_points_bin_as_one_at_a_time() {
        let points = [
            (1, Class::Normal, 1.0),
            (5, Class::Normal, 1.0),
            (1, Class::Unclassified, 1.0),
            (0, Class::Normal, 1.0),
            (6, Class::Obstacle, 1.0),
            (6, Class::Reflection, 0.7),
            (2, Class::Glass, 0.95),
        ];
        let mut together = Reliability::default();
        together.add_points(points);
        let mut alone = Reliability::default();
        for (l, c, p) in points {
            alone.add_point(l, c, p);
        }
        for (a, b) in together.bins.iter().zip(&alone.bins) {
            assert_eq!((a.points, a.correct), (b.points, b.correct));
            assert!(close(a.confidence_sum, b.confidence_sum));
        }
        assert_eq!(
            (together.confident, together.confident_correct),
            (alone.confident, alone.confident_correct)
        );
        assert_eq!(together.points(), 5);
    }

    /// Hand-computed: six binned points in two bins, three left out.
    #[test]
    fn bins_count_and_score_like_the_confusion() {
        let mut r = Reliability::default();
        // (label, class, confidence)
        r.add_points([
            // Bin 9: glass (2) and mirror (3) both count as the
            // reflective-surface class; a Normal mistaken for glass.
            (2, Class::Glass, 0.95),
            (3, Class::Glass, 1.0),
            (1, Class::Glass, 0.9),
            (5, Class::Reflection, 0.95),
            // Bin 2: one right, one wrong.
            (6, Class::Obstacle, 0.25),
            (5, Class::Normal, 0.25),
            // Left out: unclassified, ignored labels 0 and 4, a NaN.
            (1, Class::Unclassified, 0.5),
            (0, Class::Normal, 0.5),
            (4, Class::Glass, 0.5),
            (1, Class::Normal, f32::NAN),
        ]);
        assert_eq!(r.points(), 6);
        let rep = r.report();
        assert_eq!(rep.bins.len(), BINS);
        let b9 = &rep.bins[9];
        assert_eq!((b9.points, b9.correct), (4, 3));
        assert!(close(b9.accuracy, 0.75));
        assert!(close(b9.mean_confidence, 0.95), "{}", b9.mean_confidence);
        let b2 = &rep.bins[2];
        assert_eq!((b2.points, b2.correct), (2, 1));
        assert!(close(b2.mean_confidence, 0.25));
        assert!(close(b2.accuracy, 0.5));
        assert!(rep.bins[5].mean_confidence.is_nan());
        assert_eq!(rep.bins[5].points, 0);
        // ECE = 4/6 * |0.75 - 0.95| + 2/6 * |0.5 - 0.25| = 0.1333 + 0.0833.
        assert!(
            close(rep.ece, 4.0 / 6.0 * 0.2 + 2.0 / 6.0 * 0.25),
            "{}",
            rep.ece
        );
        assert!(close(rep.accuracy, 4.0 / 6.0));
        // Confident: the four of bin 9 (0.9 included), three correct.
        assert_eq!(rep.confident_points, 4);
        assert!(close(rep.confident_accuracy, 0.75));
        let md = rep.markdown();
        assert!(md.contains("| [0.9, 1.0] | 4 | 0.950 | 0.750 |"), "{md}");
        assert!(md.contains("| [0.5, 0.6) | 0 | – | – |"), "{md}");
        assert!(md.contains("4 points, 75.0% of them correct"), "{md}");
    }

    /// Bin edges: 0 in the first bin, 0.1 in the second, 1 in the last;
    /// values outside [0, 1] are refused.
    #[test]
    fn bin_edges() {
        assert_eq!(bin_of(0.0), 0);
        assert_eq!(bin_of(0.1), 1);
        assert_eq!(bin_of(0.7), 7);
        assert_eq!(bin_of(0.9), 9);
        assert_eq!(bin_of(0.999), 9);
        assert_eq!(bin_of(1.0), 9);
        let mut r = Reliability::default();
        r.add_point(1, Class::Normal, 1.5);
        r.add_point(1, Class::Normal, -0.1);
        assert_eq!(r.points(), 0);
        let rep = r.report();
        assert!(rep.ece.is_nan() && rep.confident_accuracy.is_nan());
    }

    /// A perfectly calibrated set has no calibration error; merging two
    /// accumulators is adding their points.
    #[test]
    fn calibrated_points_have_no_error_and_merge_adds() {
        let mut a = Reliability::default();
        // Bin 5: confidence 0.55, 11 of 20 correct.
        for i in 0..20 {
            let class = if i < 11 { Class::Normal } else { Class::Glass };
            a.add_point(1, class, 0.55);
        }
        let mut b = Reliability::default();
        // Bin 9: confidence 1, all correct.
        b.add(&[6, 6], &[Class::Obstacle, Class::Obstacle], &[1.0, 1.0]);
        let mut all = a;
        all.merge(&b);
        assert_eq!(all.points(), 22);
        let rep = all.report();
        assert!(rep.ece.abs() < 1e-6, "{}", rep.ece);
        assert_eq!(rep.confident_points, 2);
        assert!(close(rep.confident_accuracy, 1.0));
        // JSON: empty bins' means are null.
        let json = serde_json::to_value(&rep).unwrap();
        assert!(json["bins"][0]["mean_confidence"].is_null());
        assert_eq!(json["bins"][5]["points"], 20);
    }
}
