//! The README's headline: our plane-optimized (default) and Reflection
//! SLAM results on every labelled dataset of at least ten frames, each
//! marked against the range of the paper's published values for the same
//! method.

use std::fmt::Write as _;

use super::{data_label, italic, pct, row};
use crate::published::{self, PrecisionRecallRow, RemovalRow};
use crate::{OdometryOutcome, Results};
use specular::classify::Class;
use specular::eval::Metrics;

/// A headline metric: its name, the published values it is set against,
/// and how to read ours.
type Metric = (&'static str, Vec<f64>, Box<dyn Fn(&Metrics) -> f64>);

/// Ours against the published value range: "▲" above every published
/// sequence, "▼" below every one, nothing in between.
fn versus(ours: f64, published: &[f64]) -> String {
    let published: Vec<f64> = published
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    let mark = if !ours.is_finite() || published.is_empty() {
        ""
    } else if published.iter().all(|&p| ours > p) {
        " ▲"
    } else if published.iter().all(|&p| ours < p) {
        " ▼"
    } else {
        ""
    };
    format!("{}{mark}", pct(ours))
}

/// The three removal metrics, against the published `rows`.
fn removal_metrics(rows: &[&RemovalRow]) -> Vec<Metric> {
    vec![
        (
            "Non-reflection precision",
            rows.iter().map(|r| r.non_reflection_precision).collect(),
            Box::new(|m| m.non_reflection_precision),
        ),
        (
            "Indoor precision",
            rows.iter().map(|r| r.indoor_precision).collect(),
            Box::new(|m| m.indoor_precision),
        ),
        (
            "Reflection removal rate",
            rows.iter().map(|r| r.reflection_removal).collect(),
            Box::new(|m| m.reflection_removal),
        ),
    ]
}

/// Precision and recall of each class, against the published `rows`.
fn precision_recall_metrics(rows: &[&PrecisionRecallRow]) -> Vec<Metric> {
    type Published = fn(&PrecisionRecallRow) -> (f64, f64);
    let classes: [(&str, &str, Class, Published); 4] = [
        ("Normal precision", "Normal recall", Class::Normal, |r| {
            r.normal
        }),
        (
            "Glass/Mirror precision",
            "Glass/Mirror recall",
            Class::Glass,
            |r| r.glass,
        ),
        (
            "Reflection precision",
            "Reflection recall",
            Class::Reflection,
            |r| r.reflection,
        ),
        (
            "Outdoor precision",
            "Outdoor recall",
            Class::Obstacle,
            |r| r.obstacle,
        ),
    ];
    let mut metrics: Vec<Metric> = Vec::new();
    for (precision, recall, class, published) in classes {
        metrics.push((
            precision,
            rows.iter().map(|r| published(r).0).collect(),
            Box::new(move |m| m.class(class).precision),
        ));
        metrics.push((
            recall,
            rows.iter().map(|r| published(r).1).collect(),
            Box::new(move |m| m.class(class).recall),
        ));
    }
    metrics
}

/// The headline: our plane-optimized (default) and Reflection SLAM results
/// on every dataset of at least ten frames against the paper's own
/// results for the same methods.
pub fn headline(results: &Results) -> String {
    let datasets: Vec<&str> = results
        .datasets
        .iter()
        .filter(|d| d.frames >= 10 && d.labelled)
        .map(|d| d.name.as_str())
        .collect();
    let mut s = String::new();
    // A row: the metric's cells, then one cell per dataset.
    let dataset_row = |s: &mut String, first: [String; 2], cell: &dyn Fn(&str) -> String| {
        row(s, first.into_iter().chain(datasets.iter().map(|d| cell(d))));
    };
    let header = |s: &mut String, first: [&str; 2]| {
        dataset_row(s, first.map(String::from), &|d| data_label(results, d));
        s.push_str("|---|---|");
        for _ in &datasets {
            s.push_str("---:|");
        }
        s.push('\n');
    };

    // Plane-optimized (default) vs the published Plane Optimized, seq 1-3.
    let po: Vec<&PrecisionRecallRow> = published::PRECISION_RECALL
        .iter()
        .filter(|r| r.method == published::PLANE_OPTIMIZED)
        .collect();
    let rm: Vec<&RemovalRow> = published::REMOVAL
        .iter()
        .filter(|r| r.method == published::PLANE_OPTIMIZED)
        .collect();
    let mut metrics = removal_metrics(&rm);
    metrics.extend(precision_recall_metrics(&po));
    s.push_str("**Plane-optimized, our defaults, vs the paper's Plane Optimized** (published values: 3DRef sequences 1 / 2 / 3):\n\n");
    header(&mut s, ["metric", "published seq 1 / 2 / 3"]);
    for (name, published_values, get) in &metrics {
        let published = published_values
            .iter()
            .map(|v| pct(*v))
            .collect::<Vec<_>>()
            .join(" / ");
        dataset_row(&mut s, [name.to_string(), italic(published)], &|d| {
            results
                .classification
                .iter()
                .find(|r| r.dataset == d && r.method == "plane-optimized (default)")
                .and_then(|r| r.metrics.as_ref())
                .map_or("–".into(), |m| versus(get(m), published_values))
        });
    }

    // Reflection SLAM vs the published Reflection SLAM (part of seq 3).
    let iou = published::SLAM_IOU[4];
    let mut slam_metrics: Vec<Metric> = vec![("Total", vec![iou.total], Box::new(|m| m.accuracy))];
    for (name, published, class) in [
        ("IoU Normal", iou.normal, Class::Normal),
        ("IoU Glass/Mirror", iou.glass, Class::Glass),
        ("IoU Reflection", iou.reflection, Class::Reflection),
        ("IoU Obstacle", iou.obstacle, Class::Obstacle),
    ] {
        slam_metrics.push((name, vec![published], Box::new(move |m| m.class(class).iou)));
    }
    slam_metrics.extend(removal_metrics(&[&published::SLAM_REMOVAL[4]]));
    for backend in crate::slam_backends() {
        let _ = write!(
            s,
            "\n**Reflection SLAM [{backend}] vs the paper's Reflection SLAM** (published: part of 3DRef sequence 3):\n\n"
        );
        header(&mut s, ["metric", "published"]);
        let slam = |d: &str| {
            results
                .slam
                .iter()
                .find(|r| r.dataset == d && r.backend == backend)
        };
        for (name, published_values, get) in &slam_metrics {
            let first = [name.to_string(), italic(pct(published_values[0]))];
            dataset_row(&mut s, first, &|d| {
                slam(d)
                    .and_then(|r| r.metrics.as_ref())
                    .map_or("–".into(), |m| versus(get(m), published_values))
            });
        }
        let first = ["ATE RMSE (m), Reflection SLAM".to_string(), String::new()];
        dataset_row(&mut s, first, &|d| {
            slam(d).map_or("–".into(), |r| format!("{:.3}", r.trajectory.ate_rmse))
        });
    }
    let first = ["ATE RMSE (m), KISS-ICP".to_string(), String::new()];
    dataset_row(&mut s, first, &|d| match results
        .odometry
        .iter()
        .find(|r| r.dataset == d)
        .map(|r| &r.outcome)
    {
        Some(OdometryOutcome::Ran(t)) => format!("{:.3}", t.ate_rmse),
        Some(OdometryOutcome::NotRun(_)) => "not run".into(),
        None => "–".into(),
    });
    s.push_str("\n▲ above every published value of the row, ▼ below every one. Different data: the paper scored whole 3DRef sequences, we score ten real frames and simulated scenes.\n");
    s
}
