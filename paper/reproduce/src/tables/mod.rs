//! The results rendered as Markdown in the paper's table layouts, the
//! published values first (in italics), ours below them in the same
//! columns.
//!
//! This module holds the deterministic tables of `tables.md` and the cell
//! and row helpers they share; [`headline()`] is the README's summary of our
//! results against the paper's, [`timing_markdown`] the machine-dependent timing
//! table.

mod headline;
mod timing_table;

pub use headline::headline;
pub use timing_table::timing_markdown;

use std::fmt::Write as _;

use super::published;
use super::{OdometryOutcome, Results};
use specular::classify::Class;
use specular::eval::{Metrics, TrajectoryError};

/// The real dataset compared with the original code's figures.
pub const TEN_FRAMES: &str = "3dref-seq1-demo";

/// A percentage with two decimals, "–" when undefined.
fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "–".into()
    }
}

/// "precision / recall".
fn pr(p: f64, r: f64) -> String {
    format!("{} / {}", pct(p), pct(r))
}

/// A published value: in italics.
fn italic(v: impl std::fmt::Display) -> String {
    format!("*{v}*")
}

/// One Markdown table row, `| a | b |`, and a new line; an empty cell is
/// written `| |`.
fn row<S: AsRef<str>>(s: &mut String, cells: impl IntoIterator<Item = S>) {
    s.push('|');
    for cell in cells {
        match cell.as_ref() {
            "" => s.push_str(" |"),
            c => {
                let _ = write!(s, " {c} |");
            }
        }
    }
    s.push('\n');
}

/// "name (N frames)" for one of our datasets.
fn data_label(results: &Results, name: &str) -> String {
    match results.datasets.iter().find(|d| d.name == name) {
        Some(d) => format!("{name} ({} frames)", d.frames),
        None => name.to_string(),
    }
}

/// Our classification rows whose method starts with `prefix`.
fn ours<'a>(results: &'a Results, prefix: &str) -> Vec<(&'a str, &'a str, &'a Metrics)> {
    results
        .classification
        .iter()
        .filter(|r| r.method.starts_with(prefix))
        .filter_map(|r| Some((r.dataset.as_str(), r.method.as_str(), r.metrics.as_ref()?)))
        .collect()
}

/// The paper's methods of the classification tables, each with the prefix
/// of our rows of the same method (none for the learned baselines).
const CLASSIFICATION_GROUPS: [(&str, Option<&str>); 4] = [
    ("Cylinder3D", None),
    ("Minkowski", None),
    (published::ZHAO, Some("single-scan")),
    (published::PLANE_OPTIMIZED, Some("plane-optimized")),
];

/// The three removal columns (non-reflection precision, indoor precision,
/// reflection removal rate) of a published row, in italics.
fn published_removal_cells(r: &published::RemovalRow) -> [String; 3] {
    [
        r.non_reflection_precision,
        r.indoor_precision,
        r.reflection_removal,
    ]
    .map(|v| italic(pct(v)))
}

/// The same three columns of our metrics.
fn removal_cells(m: &Metrics) -> [String; 3] {
    [
        m.non_reflection_precision,
        m.indoor_precision,
        m.reflection_removal,
    ]
    .map(pct)
}

/// Every deterministic table, in the paper's order, each under a heading
/// with `command`.
pub fn markdown(results: &Results, command: &str) -> String {
    let mut s = String::new();
    let produced = format!("Produced by `{command}`.\n\n");
    if results.quick {
        s.push_str("> **--quick run**: the simulated sequences are cut to 12 frames from the middle of their trajectories and the timing runs once; these are not the reproduction's numbers.\n\n");
    }
    s.push_str("### Label statistics (paper: Table \"Percent of Point Label in Each Sequence\", Hesai rows)\n\n");
    s.push_str(&produced);
    s.push_str(&label_table(results));
    if let Some(t) = original_code_table(results) {
        s.push_str("\n### Ten real frames: original C++ code vs this port (plane-optimized)\n\n");
        s.push_str(&produced);
        s.push_str(&t);
    }
    s.push_str("\n### Classification Precision/Recall (paper: `tab:precisionandrecall`)\n\n");
    s.push_str(&produced);
    s.push_str(&precision_recall_table(results));
    s.push_str("\n### Filtered point cloud precision and reflection removal rate (paper: `tab:precisionandremoval`)\n\n");
    s.push_str(&produced);
    s.push_str(&removal_table(results));
    s.push_str("\n### Classification with Reflection SLAM, IoU (paper: `tab:reflectiveslam`)\n\n");
    s.push_str(&produced);
    s.push_str(&slam_iou_table(results));
    s.push_str(
        "\n### Reflection removal with Reflection SLAM (paper: `tab:reflectiveslamremoval`)\n\n",
    );
    s.push_str(&produced);
    s.push_str(&slam_removal_table(results));
    s.push_str("\n### Trajectory error: Reflection SLAM vs KISS-ICP (not in the paper)\n\n");
    s.push_str(&produced);
    s.push_str(&trajectory_table(results));
    s
}

fn label_table(results: &Results) -> String {
    let mut s = String::from(
        "| data / size | Normal | Glass | Mirror | OtherRef | Reflection | Obstacle | unlabeled |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in published::LABEL_SHARES {
        let name = format!("published: 3DRef seq {} / {} (Hesai)", r.sequence, r.frames);
        let shares = r.shares[..6].iter().map(|&v| italic(pct(v)));
        row(
            &mut s,
            [italic(name)]
                .into_iter()
                .chain(shares)
                .chain([String::new()]),
        );
    }
    for d in &results.datasets {
        let n = d.points.max(1) as f64;
        let p = |l: usize| pct(100.0 * d.by_label[l] as f64 / n);
        let name = format!("{} / {}", d.name, d.frames);
        row(
            &mut s,
            [name].into_iter().chain([1, 2, 3, 4, 5, 6, 0].map(p)),
        );
    }
    s.push_str("\nShares of all points (both returns). Published values in italics.\n");
    s
}

fn original_code_table(results: &Results) -> Option<String> {
    let rows = ours(results, "plane-optimized");
    let rows: Vec<_> = rows.iter().filter(|(d, _, _)| *d == TEN_FRAMES).collect();
    if rows.is_empty() {
        return None;
    }
    let (acc, removal, iou) = published::ORIGINAL_CODE_TEN_FRAMES;
    let mut s = String::from(
        "| method | accuracy | IoU Normal | IoU Glass | IoU Reflection | IoU Obstacle | reflection removal |\n|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let one_decimal = |v: f64| italic(format!("{v:.1}"));
    row(
        &mut s,
        [
            italic("original C++ code (project brief)"),
            one_decimal(acc),
        ]
        .into_iter()
        .chain(iou.map(one_decimal))
        .chain([one_decimal(removal)]),
    );
    for (_, method, m) in rows {
        let iou = |k: Class| pct(m.class(k).iou);
        row(
            &mut s,
            [
                method.to_string(),
                pct(m.accuracy),
                iou(Class::Normal),
                iou(Class::Glass),
                iou(Class::Reflection),
                iou(Class::Obstacle),
                pct(m.reflection_removal),
            ],
        );
    }
    Some(s)
}

fn precision_recall_table(results: &Results) -> String {
    let mut s = String::from(
        "| method | sequence / data | Normal P / R | Glass/Mirror P / R | Reflection P / R | Outdoor (obstacle) P / R | Indoor P / R |\n|---|---|---|---|---|---|---|\n",
    );
    for (paper_name, our_prefix) in CLASSIFICATION_GROUPS {
        for r in published::PRECISION_RECALL
            .iter()
            .filter(|r| r.method == paper_name)
        {
            let cell = |(p, r): (f64, f64)| italic(pr(p, r));
            row(
                &mut s,
                [
                    italic(format!("{} (published)", r.method)),
                    italic(format!("3DRef seq {}", r.sequence)),
                    cell(r.normal),
                    cell(r.glass),
                    cell(r.reflection),
                    cell(r.obstacle),
                    String::new(),
                ],
            );
        }
        let Some(prefix) = our_prefix else { continue };
        for (data, method, m) in ours(results, prefix) {
            let c = |k: Class| pr(m.class(k).precision, m.class(k).recall);
            row(
                &mut s,
                [
                    method.to_string(),
                    data_label(results, data),
                    c(Class::Normal),
                    c(Class::Glass),
                    c(Class::Reflection),
                    c(Class::Obstacle),
                    pr(m.indoor_precision, m.confusion.indoor_recall()),
                ],
            );
        }
    }
    s.push_str("\nPercent. Published values in italics; Zhao's method is our `single-scan`. Indoor = Normal ∪ Glass/Mirror (the paper gives only its precision, next table). `plane-optimized (paper)` keeps only planes seen in 10 frames (`map.min_observations`), so on the 3-frame sample it keeps none and calls every point Normal.\n");
    s
}

fn removal_table(results: &Results) -> String {
    let mut s = String::from(
        "| method | sequence / data | Non-reflection precision | Indoor precision | Reflection removal rate |\n|---|---|---:|---:|---:|\n",
    );
    for (paper_name, our_prefix) in CLASSIFICATION_GROUPS {
        for r in published::REMOVAL.iter().filter(|r| r.method == paper_name) {
            let name = [
                italic(format!("{} (published)", r.method)),
                italic(format!("3DRef seq {}", r.sequence)),
            ];
            row(&mut s, name.into_iter().chain(published_removal_cells(r)));
        }
        let Some(prefix) = our_prefix else { continue };
        for (data, method, m) in ours(results, prefix) {
            let name = [method.to_string(), data_label(results, data)];
            row(&mut s, name.into_iter().chain(removal_cells(m)));
        }
    }
    s.push_str("\nPercent. Published values in italics. Unclassified points count as removed.\n");
    s
}

/// Our rows of the SLAM comparison, dataset by dataset: single-scan,
/// plane-optimized (default, true poses), Reflection SLAM per back-end.
fn slam_comparison_rows(results: &Results) -> Vec<(String, String, &Metrics)> {
    let mut rows = Vec::new();
    for d in &results.datasets {
        for r in results
            .classification
            .iter()
            .filter(|r| r.dataset == d.name)
        {
            if r.method == "plane-optimized (paper)" {
                continue;
            }
            if let Some(m) = &r.metrics {
                let name = if r.method.starts_with("plane-optimized") {
                    format!("{}, true poses", r.method)
                } else {
                    r.method.clone()
                };
                rows.push((data_label(results, &d.name), name, m));
            }
        }
        for r in results.slam.iter().filter(|r| r.dataset == d.name) {
            if let Some(m) = &r.metrics {
                rows.push((
                    data_label(results, &d.name),
                    format!("Reflection SLAM [{}] (default)", r.backend),
                    m,
                ));
            }
        }
    }
    rows
}

/// The data cell of the paper's Reflection SLAM rows.
const SLAM_DATA: &str = "*3DRef seq 3, ~1200 frames*";

fn slam_iou_table(results: &Results) -> String {
    let mut s = String::from(
        "| method | data | Total | Normal | Glass/Mirror | Reflection | Obstacle |\n|---|---|---:|---:|---:|---:|---:|\n",
    );
    for r in published::SLAM_IOU {
        let values = [r.total, r.normal, r.glass, r.reflection, r.obstacle];
        let name = [
            italic(format!("{} (published)", r.method)),
            SLAM_DATA.into(),
        ];
        row(
            &mut s,
            name.into_iter().chain(values.map(|v| italic(pct(v)))),
        );
    }
    for (data, method, m) in slam_comparison_rows(results) {
        let iou = |k: Class| pct(m.class(k).iou);
        row(
            &mut s,
            [
                method,
                data,
                pct(m.accuracy),
                iou(Class::Normal),
                iou(Class::Glass),
                iou(Class::Reflection),
                iou(Class::Obstacle),
            ],
        );
    }
    s.push_str("\nIoU in percent; \"Total\" is the share of correctly classified points (the paper's Total is above every class IoU, so it is not their mean). Published values in italics.\n");
    s
}

fn slam_removal_table(results: &Results) -> String {
    let mut s = String::from(
        "| method | data | Non-reflection precision | Indoor precision | Reflection removal rate |\n|---|---|---:|---:|---:|\n",
    );
    for r in published::SLAM_REMOVAL {
        let name = [
            italic(format!("{} (published)", r.method)),
            SLAM_DATA.into(),
        ];
        row(&mut s, name.into_iter().chain(published_removal_cells(r)));
    }
    for (data, method, m) in slam_comparison_rows(results) {
        row(&mut s, [method, data].into_iter().chain(removal_cells(m)));
    }
    s.push_str("\nPercent. Published values in italics.\n");
    s
}

/// The five error columns of a trajectory.
fn trajectory_cells(t: &TrajectoryError) -> [String; 5] {
    [
        format!("{:.3}", t.ate_rmse),
        format!("{:.3}", t.ate_max),
        pct(t.rpe_translation_percent),
        if t.rpe_rotation_deg_per_m.is_finite() {
            format!("{:.3}", t.rpe_rotation_deg_per_m)
        } else {
            "–".into()
        },
        pct(t.drift_percent),
    ]
}

fn trajectory_table(results: &Results) -> String {
    let mut s = String::from(
        "| data | path (m) | method | ATE RMSE (m) | ATE max (m) | RPE (%) | RPE (deg/m) | drift (%) | degenerate frames |\n|---|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for d in &results.datasets {
        let data = data_label(results, &d.name);
        for r in results.slam.iter().filter(|r| r.dataset == d.name) {
            let t = &r.trajectory;
            let method = format!("Reflection SLAM [{}]", r.backend);
            let name = [data.clone(), format!("{:.2}", t.path_length), method];
            let degenerate = r.degenerate_frames.to_string();
            row(
                &mut s,
                name.into_iter()
                    .chain(trajectory_cells(t))
                    .chain([degenerate]),
            );
        }
        for r in results.odometry.iter().filter(|r| r.dataset == d.name) {
            match &r.outcome {
                OdometryOutcome::Ran(t) => {
                    let name = [
                        data.clone(),
                        format!("{:.2}", t.path_length),
                        r.method.clone(),
                    ];
                    row(
                        &mut s,
                        name.into_iter()
                            .chain(trajectory_cells(t))
                            .chain(["–".to_string()]),
                    );
                }
                OdometryOutcome::NotRun(why) => {
                    let name = [data.clone(), String::new(), r.method.clone(), why.clone()];
                    row(&mut s, name.into_iter().chain([""; 5].map(String::from)));
                }
            }
        }
    }
    s.push_str("\nBoth scored by `specular::eval::trajectory_error` against the true poses: ATE after a rigid (Umeyama, no scale) alignment, RPE over 1 m segments, drift = final error / path length. KISS-ICP sees the first returns only.\n");
    s
}
