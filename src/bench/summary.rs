//! Per-family statistics of the benchmark's seeds: the median, the 10th
//! percentile on the bad side (the 90th for the ATE, where lower is
//! better) and the worst seed, and the Markdown table that shows them.
//!
//! A seed whose truth lacks a class (no obstacle behind glass) has no
//! score for it: such values are left out of that metric's statistics,
//! and the table says over how many seeds each figure is.

use serde::{Deserialize, Serialize};

use super::SeedResult;

/// The metrics summarised: (key, column title, whether lower is better).
pub const METRICS: [(&str, &str, bool); 6] = [
    ("miou", "mIoU", false),
    ("reflection_removal", "refl. removal", false),
    ("obstacle_iou", "obstacle IoU", false),
    ("normal_recall", "normal recall", false),
    ("glass_iou", "glass IoU", false),
    ("ate", "ATE (m)", true),
];

/// The statistics of one metric over seeds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    /// The median.
    pub median: f64,
    /// The 10th percentile on the bad side (the 90th where lower is
    /// better), linearly interpolated.
    pub p10: f64,
    /// The worst seed's value.
    pub worst: f64,
    /// Seeds with a value.
    pub n: usize,
}

impl Stat {
    /// The statistics of `values` (NaN values left out; all NaN when none
    /// is left).
    pub fn of(values: impl IntoIterator<Item = f64>, lower_is_better: bool) -> Self {
        let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return Self {
                median: f64::NAN,
                p10: f64::NAN,
                worst: f64::NAN,
                n: 0,
            };
        }
        v.sort_by(f64::total_cmp);
        if lower_is_better {
            v.reverse();
        }
        Self {
            median: quantile(&v, 0.5),
            p10: quantile(&v, 0.1),
            worst: v[0],
            n: v.len(),
        }
    }
}

/// The `q` quantile of sorted `v` (linear between order statistics).
fn quantile(v: &[f64], q: f64) -> f64 {
    let pos = q * (v.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

/// The statistics of one family (or of all), one [`Stat`] per entry of
/// [`METRICS`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FamilySummary {
    /// Family name (`all` for every family together).
    pub family: String,
    /// Seeds run.
    pub seeds: usize,
    /// One per metric, in the order of [`METRICS`].
    pub stats: Vec<Stat>,
}

impl FamilySummary {
    /// The statistics of `results` under `name`.
    pub fn of<'a>(name: &str, results: impl IntoIterator<Item = &'a SeedResult> + Clone) -> Self {
        let seeds = results.clone().into_iter().count();
        let stats = METRICS
            .iter()
            .map(|(key, _, lower)| {
                Stat::of(results.clone().into_iter().map(|r| r.metric(key)), *lower)
            })
            .collect();
        Self {
            family: name.to_string(),
            seeds,
            stats,
        }
    }
}

/// Per family, in the order the families first appear, and over all.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// One per family.
    pub families: Vec<FamilySummary>,
    /// Every seed of every family together.
    pub all: FamilySummary,
}

impl Summary {
    /// Summarise `results`.
    pub fn of(results: &[SeedResult]) -> Self {
        let mut names: Vec<&str> = Vec::new();
        for r in results {
            if !names.contains(&r.family.as_str()) {
                names.push(&r.family);
            }
        }
        let families = names
            .iter()
            .map(|name| FamilySummary::of(name, results.iter().filter(|r| r.family == *name)))
            .collect();
        Self {
            families,
            all: FamilySummary::of("all", results.iter()),
        }
    }

    /// The table: one row per family and one over all; each cell
    /// `median / p10 / worst`.
    pub fn markdown(&self) -> String {
        let mut s = String::from("| family | seeds |");
        for (_, title, _) in METRICS {
            s.push_str(&format!(" {title} |"));
        }
        s.push_str("\n|---|---:|");
        for _ in METRICS {
            s.push_str("---:|");
        }
        s.push('\n');
        for f in self.families.iter().chain(std::iter::once(&self.all)) {
            let name = if f.family == "all" {
                "**all**".to_string()
            } else {
                f.family.clone()
            };
            s.push_str(&format!("| {name} | {} |", f.seeds));
            for (stat, (key, _, _)) in f.stats.iter().zip(METRICS) {
                s.push_str(&format!(" {} |", cell(stat, key == "ate", f.seeds)));
            }
            s.push('\n');
        }
        s
    }
}

/// `median / p10 / worst`, with the count when some seeds had no value.
fn cell(stat: &Stat, metres: bool, seeds: usize) -> String {
    if stat.n == 0 {
        return "–".into();
    }
    let f = |v: f64| {
        if metres {
            format!("{v:.3}")
        } else {
            format!("{v:.1}")
        }
    };
    let mut c = format!("{} / {} / {}", f(stat.median), f(stat.p10), f(stat.worst));
    if stat.n < seeds {
        c.push_str(&format!(" ({} seeds)", stat.n));
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_take_the_bad_side() {
        let v = [50.0, 90.0, 70.0, 80.0, 60.0, f64::NAN];
        let s = Stat::of(v, false);
        assert_eq!((s.median, s.worst, s.n), (70.0, 50.0, 5));
        assert!((s.p10 - 54.0).abs() < 1e-12);
        // Lower is better: the worst is the largest, p10 near it.
        let s = Stat::of([0.01, 0.05, 0.02], true);
        assert_eq!((s.median, s.worst), (0.02, 0.05));
        assert!((s.p10 - 0.044).abs() < 1e-12);
        assert_eq!(Stat::of([f64::NAN], false).n, 0);
    }
}
