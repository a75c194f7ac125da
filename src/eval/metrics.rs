//! Confusion counts and the metrics derived from them.

use serde::{Deserialize, Serialize};

use crate::classify::Class;

/// The four scored classes, in table order.
pub const EVAL_CLASSES: [Class; 4] = [
    Class::Normal,
    Class::Glass,
    Class::Reflection,
    Class::Obstacle,
];

/// Index of a scored class in [`EVAL_CLASSES`].
fn class_index(c: Class) -> Option<usize> {
    EVAL_CLASSES.iter().position(|&e| e == c)
}

/// The scored class of a 3DRef label, `None` for ignored labels (0, 4).
pub fn truth_class(label: u8) -> Option<Class> {
    match label {
        1 => Some(Class::Normal),
        2 | 3 => Some(Class::Glass),
        5 => Some(Class::Reflection),
        6 => Some(Class::Obstacle),
        _ => None,
    }
}

/// Counts of (true class, predicted class); column 0 is "unclassified".
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Confusion {
    /// `counts[t][p]`: true class `t` (N, G, R, O), prediction `p`
    /// (unclassified, N, G, R, O).
    pub counts: [[u64; 5]; 4],
    /// Points with an ignored label (0 or 4).
    pub ignored: u64,
    /// Every point by `[truth label id][prediction id]`: label ids 0-6 as
    /// in 3DRef (7 holds any other id), prediction ids 0 (unclassified),
    /// 1, 2, 5 and 6; ignored labels included, so a reader sees where
    /// mirrors (3) and other reflective surfaces (4) went.
    #[serde(default)]
    pub by_label: [[u64; 8]; 8],
}

/// Names of the 3DRef label ids, row order of [`Confusion::by_label`].
pub const LABEL_NAMES: [&str; 8] = [
    "unlabeled",
    "normal",
    "glass",
    "mirror",
    "other reflective",
    "reflection",
    "obstacle",
    "other id",
];

impl Confusion {
    /// Add one frame's labels and predictions (same length and order).
    pub fn add(&mut self, labels: &[u8], predictions: &[Class]) {
        self.add_pairs(labels.iter().copied().zip(predictions.iter().copied()));
    }

    /// Add (label, prediction) pairs. Counted in a histogram of the raw
    /// pairs first (class ids are below 8), mapped to the table once.
    pub fn add_pairs(&mut self, pairs: impl IntoIterator<Item = (u8, Class)>) {
        let mut hist = vec![0u64; 256 * 8];
        for (l, p) in pairs {
            hist[(l as usize) << 3 | (p.id() as usize & 7)] += 1;
        }
        for (label, row) in hist.chunks_exact(8).enumerate() {
            let n: u64 = row.iter().sum();
            if n == 0 {
                continue;
            }
            for (pred, &count) in row.iter().enumerate() {
                self.by_label[label.min(7)][pred] += count;
            }
            let Some(t) = truth_class(label as u8).and_then(class_index) else {
                self.ignored += n;
                continue;
            };
            for (id, &count) in row.iter().enumerate() {
                let col = class_index(Class::from_id(id as u32)).map_or(0, |k| k + 1);
                self.counts[t][col] += count;
            }
        }
    }

    /// Merge another confusion into this one.
    pub fn merge(&mut self, other: &Confusion) {
        for t in 0..4 {
            for p in 0..5 {
                self.counts[t][p] += other.counts[t][p];
            }
        }
        self.ignored += other.ignored;
        for (a, b) in self.by_label.iter_mut().zip(&other.by_label) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }

    /// The truth-by-prediction counts of every label id as a Markdown table
    /// (rows: labels present; columns: the prediction ids).
    pub fn label_table(&self) -> String {
        const PREDICTIONS: [(usize, &str); 5] = [
            (0, "unclassified (0)"),
            (1, "normal (1)"),
            (2, "reflective surface (2)"),
            (5, "reflection (5)"),
            (6, "obstacle (6)"),
        ];
        let mut s = String::from("| truth \\ prediction |");
        for (_, name) in PREDICTIONS {
            s.push_str(&format!(" {name} |"));
        }
        s.push_str(" points |\n|---|");
        s.push_str(&"---:|".repeat(PREDICTIONS.len() + 1));
        s.push('\n');
        for (label, row) in self.by_label.iter().enumerate() {
            let n: u64 = row.iter().sum();
            if n == 0 {
                continue;
            }
            s.push_str(&format!("| {} ({label}) |", LABEL_NAMES[label]));
            for (id, _) in PREDICTIONS {
                s.push_str(&format!(" {} |", row[id]));
            }
            s.push_str(&format!(" {n} |\n"));
        }
        s
    }

    /// Of the true Normal and Glass points, the share predicted Normal or
    /// Glass, in percent (the recall of the paper's "Indoor Points").
    pub fn indoor_recall(&self) -> f64 {
        let c = &self.counts;
        let truth: u64 = c[0].iter().chain(&c[1]).sum();
        let kept = c[0][1] + c[0][2] + c[1][1] + c[1][2];
        if truth == 0 {
            f64::NAN
        } else {
            100.0 * kept as f64 / truth as f64
        }
    }

    /// Points scored (labels not ignored).
    pub fn total(&self) -> u64 {
        self.counts.iter().flatten().sum()
    }

    /// The metrics of these counts.
    pub fn metrics(&self) -> Metrics {
        let c = &self.counts;
        let pct = |num: u64, den: u64| {
            if den == 0 {
                f64::NAN
            } else {
                100.0 * num as f64 / den as f64
            }
        };
        let per_class: Vec<ClassScores> = (0..4)
            .map(|k| {
                let tp = c[k][k + 1];
                let truth: u64 = c[k].iter().sum();
                let predicted: u64 = (0..4).map(|t| c[t][k + 1]).sum();
                ClassScores {
                    class: EVAL_CLASSES[k],
                    precision: pct(tp, predicted),
                    recall: pct(tp, truth),
                    iou: pct(tp, truth + predicted - tp),
                    truth,
                    predicted,
                }
            })
            .collect();
        let total = self.total();
        let correct: u64 = (0..4).map(|k| c[k][k + 1]).sum();
        // A class absent from the truth has no IoU to average: its false
        // predictions already count against the IoU of the classes those
        // points are (one Obstacle called Reflection in a scene without
        // reflections would otherwise weigh a quarter of the mean).
        let ious: Vec<f64> = per_class
            .iter()
            .filter(|s| s.truth > 0)
            .map(|s| s.iou)
            .collect();
        let (n, g, r) = (0, 1, 2);
        let (pn, pg, pr, po) = (1, 2, 3, 4);
        // Kept and not called reflection: predicted N, G or O.
        let kept: u64 = (0..4).map(|t| c[t][pn] + c[t][pg] + c[t][po]).sum();
        let kept_reflections = c[r][pn] + c[r][pg] + c[r][po];
        // Called indoor: predicted N or G.
        let indoor: u64 = (0..4).map(|t| c[t][pn] + c[t][pg]).sum();
        let indoor_true = c[n][pn] + c[n][pg] + c[g][pn] + c[g][pg];
        let reflections: u64 = c[r].iter().sum();
        let removed = c[r][0] + c[r][pr];
        Metrics {
            classes: per_class,
            accuracy: pct(correct, total),
            miou: if ious.is_empty() {
                f64::NAN
            } else {
                ious.iter().sum::<f64>() / ious.len() as f64
            },
            non_reflection_precision: pct(kept - kept_reflections, kept),
            indoor_precision: pct(indoor_true, indoor),
            reflection_removal: pct(removed, reflections),
            unclassified_share: pct((0..4).map(|t| c[t][0]).sum(), total),
            points: total,
            ignored: self.ignored,
            confusion: *self,
        }
    }
}

/// Precision, recall and IoU of one class, in percent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClassScores {
    /// The class.
    pub class: Class,
    /// Of the points predicted as the class, the share that are.
    pub precision: f64,
    /// Of the points that are the class, the share predicted as it.
    pub recall: f64,
    /// Intersection over union.
    pub iou: f64,
    /// Points of this class in the ground truth.
    pub truth: u64,
    /// Points predicted as this class.
    pub predicted: u64,
}

/// The paper's metrics, in percent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Normal, Glass, Reflection, Obstacle.
    pub classes: Vec<ClassScores>,
    /// Share of scored points predicted as their class.
    pub accuracy: f64,
    /// Mean IoU over the four classes, of those present in the truth.
    pub miou: f64,
    /// Of the points kept and not called reflection (N, G, O), the share that
    /// are not reflections.
    pub non_reflection_precision: f64,
    /// Of the points called N or G, the share that are N or G.
    pub indoor_precision: f64,
    /// Of the true reflections, the share predicted Reflection or left
    /// unclassified.
    pub reflection_removal: f64,
    /// Share of scored points left unclassified.
    pub unclassified_share: f64,
    /// Points scored.
    pub points: u64,
    /// Points ignored (labels 0 and 4).
    pub ignored: u64,
    /// The underlying counts.
    pub confusion: Confusion,
}

impl Metrics {
    /// Scores of one class.
    pub fn class(&self, c: Class) -> &ClassScores {
        &self.classes[class_index(c).expect("scored class")]
    }

    /// A plain-text table (the CLI prints it).
    pub fn table(&self) -> String {
        let mut s = String::new();
        s.push_str("class        precision   recall      IoU     truth  predicted\n");
        for c in &self.classes {
            s.push_str(&format!(
                "{:<12} {:>9.2} {:>8.2} {:>8.2} {:>9} {:>10}\n",
                c.class.name(),
                c.precision,
                c.recall,
                c.iou,
                c.truth,
                c.predicted
            ));
        }
        s.push_str(&format!(
            "accuracy {:.2}  mIoU {:.2}  non-reflection precision {:.2}  indoor precision {:.2}  reflection removal {:.2}  unclassified {:.2}%  ({} points, {} ignored)\n",
            self.accuracy,
            self.miou,
            self.non_reflection_precision,
            self.indoor_precision,
            self.reflection_removal,
            self.unclassified_share,
            self.points,
            self.ignored
        ));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_follow_the_paper_definitions() {
        let mut conf = Confusion::default();
        // labels: N N G R R O, ignored 0 and 4
        let labels = [1u8, 1, 2, 5, 5, 6, 0, 4];
        let preds = [
            Class::Normal,
            Class::Glass,
            Class::Glass,
            Class::Reflection,
            Class::Unclassified,
            Class::Normal,
            Class::Normal,
            Class::Normal,
        ];
        conf.add(&labels, &preds);
        // Every point is in the label table, ignored ones included.
        assert_eq!(conf.by_label.iter().flatten().sum::<u64>(), 8);
        assert_eq!(conf.by_label[5][5], 1);
        assert_eq!(conf.by_label[5][0], 1);
        assert_eq!(conf.by_label[4][1], 1);
        let table = conf.label_table();
        assert!(
            table.contains("| other reflective (4) | 0 | 1 |"),
            "{table}"
        );
        assert!(!table.contains("mirror (3)"), "{table}");
        let m = conf.metrics();
        assert_eq!(m.points, 6);
        assert_eq!(m.ignored, 2);
        assert!((m.accuracy - 50.0).abs() < 1e-9);
        let n = m.class(Class::Normal);
        assert!((n.precision - 50.0).abs() < 1e-9); // N predicted for a N and an O
        assert!((n.recall - 50.0).abs() < 1e-9);
        assert!((n.iou - 100.0 / 3.0).abs() < 1e-9);
        let g = m.class(Class::Glass);
        assert!((g.precision - 50.0).abs() < 1e-9);
        assert!((g.recall - 100.0).abs() < 1e-9);
        // Unclassified reflection counts as removed but not as recall.
        assert!((m.reflection_removal - 100.0).abs() < 1e-9);
        assert!((m.class(Class::Reflection).recall - 50.0).abs() < 1e-9);
        // Kept and not reflection: N,G,G,N (for O) -> 4 points, none reflections.
        assert!((m.non_reflection_precision - 100.0).abs() < 1e-9);
        // Indoor: predicted N or G = 4 points, 3 of them N or G truly.
        assert!((m.indoor_precision - 75.0).abs() < 1e-9);
        // Of the 3 true N/G points, all 3 predicted N or G.
        assert!((conf.indoor_recall() - 100.0).abs() < 1e-9);
    }

    #[test]
    fn a_class_absent_from_the_truth_is_not_averaged() {
        // Truth: three Normal, one Obstacle; one Normal called Reflection.
        let mut conf = Confusion::default();
        conf.add(
            &[1u8, 1, 1, 6],
            &[
                Class::Normal,
                Class::Normal,
                Class::Reflection,
                Class::Obstacle,
            ],
        );
        let m = conf.metrics();
        let n = m.class(Class::Normal).iou;
        assert!((n - 200.0 / 3.0).abs() < 1e-9, "{n}");
        // Reflection: no truth, one prediction (IoU 0); not in the mean,
        // its miss already lowers the Normal IoU.
        assert_eq!(m.class(Class::Reflection).iou, 0.0);
        assert!((m.miou - (n + 100.0) / 2.0).abs() < 1e-9, "{}", m.miou);
    }
}
