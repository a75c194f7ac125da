//! Label statistics of a sequence: the share of every 3DRef class among all
//! returns, to compare a simulated sequence with the real dataset.

use crate::cloud::Frame;

/// Point counts per 3DRef label over a set of frames. Counts of disjoint
/// frame sets add up with [`LabelCounts::merge`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LabelCounts {
    /// Frames counted.
    pub frames: u64,
    /// Points (both returns).
    pub points: u64,
    /// Return-2 points.
    pub second_returns: u64,
    /// Points per label id 0..=6 (ids above 6 count as 0, unlabeled).
    pub by_label: [u64; 7],
}

/// Shares (fractions of all points) of the classes the paper evaluates.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LabelShares {
    /// Label 1.
    pub normal: f64,
    /// Labels 2 and 3 (reflective surface points).
    pub glass_mirror: f64,
    /// Label 4.
    pub other_reflective: f64,
    /// Label 5.
    pub reflection: f64,
    /// Label 6.
    pub obstacle: f64,
    /// Label 0.
    pub unlabeled: f64,
    /// Return-2 points.
    pub second_returns: f64,
}

impl LabelCounts {
    /// Count the points of one frame.
    pub fn add(&mut self, frame: &Frame) {
        self.frames += 1;
        for p in &frame.points {
            self.points += 1;
            if p.ret == 2 {
                self.second_returns += 1;
            }
            let l = if p.label <= 6 { p.label as usize } else { 0 };
            self.by_label[l] += 1;
        }
    }

    /// Counts of one frame.
    pub fn of(frame: &Frame) -> Self {
        let mut c = Self::default();
        c.add(frame);
        c
    }

    /// Sum of two counts.
    pub fn merge(mut self, other: Self) -> Self {
        self.frames += other.frames;
        self.points += other.points;
        self.second_returns += other.second_returns;
        for (a, b) in self.by_label.iter_mut().zip(other.by_label) {
            *a += b;
        }
        self
    }

    /// Shares of the evaluated classes (all zero when there are no points).
    pub fn shares(&self) -> LabelShares {
        let n = self.points.max(1) as f64;
        let f = |c: u64| c as f64 / n;
        let l = &self.by_label;
        LabelShares {
            normal: f(l[1]),
            glass_mirror: f(l[2] + l[3]),
            other_reflective: f(l[4]),
            reflection: f(l[5]),
            obstacle: f(l[6]),
            unlabeled: f(l[0]),
            second_returns: f(self.second_returns),
        }
    }

    /// Header of the Markdown table written by [`LabelCounts::table_row`].
    pub fn table_header() -> String {
        "| scene | frames | points/frame | normal | glass+mirror | other refl. | reflection | obstacle | return 2 |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|"
            .to_string()
    }

    /// One Markdown table row (percentages) named `name`.
    pub fn table_row(&self, name: &str) -> String {
        let s = self.shares();
        let pct = |x: f64| format!("{:.1}%", 100.0 * x);
        format!(
            "| {name} | {} | {:.0} | {} | {} | {} | {} | {} | {} |",
            self.frames,
            self.points as f64 / self.frames.max(1) as f64,
            pct(s.normal),
            pct(s.glass_mirror),
            pct(s.other_reflective),
            pct(s.reflection),
            pct(s.obstacle),
            pct(s.second_returns),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Point;

    #[test]
    fn counts_add_and_merge() {
        let mk = |labels: &[u8]| Frame {
            points: labels
                .iter()
                .map(|&label| Point {
                    label,
                    ret: if label == 6 { 2 } else { 1 },
                    ..Point::default()
                })
                .collect(),
            has_labels: true,
            ..Frame::default()
        };
        let a = LabelCounts::of(&mk(&[1, 1, 2, 5]));
        let b = LabelCounts::of(&mk(&[1, 6, 9, 3]));
        let c = a.merge(b);
        assert_eq!(c.frames, 2);
        assert_eq!(c.points, 8);
        assert_eq!(c.by_label, [1, 3, 1, 1, 0, 1, 1]);
        let s = c.shares();
        assert!((s.normal - 0.375).abs() < 1e-12);
        assert!((s.glass_mirror - 0.25).abs() < 1e-12);
        assert!((s.second_returns - 0.125).abs() < 1e-12);
        assert!(c.table_row("x").starts_with("| x | 2 | 4 | 37.5% |"));
    }
}
