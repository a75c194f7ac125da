//! `bench.png`: the benchmark's seeds per family, one dot a seed, for mIoU
//! and reflection removal side by side, the median as a bar, so a reader
//! sees the spread and the worst seed, not only a mean. `reliability.png`:
//! the calibration of the per-point confidences over every seed.

use std::path::Path;

use plotters::prelude::*;

use super::plots::{plot_err, render};
use crate::bench::SeedResult;
use crate::eval::ReliabilityReport;
use crate::Result;

/// Draw `results` (grouped by family in order of appearance) into `path`.
pub fn bench_png(path: &Path, title: &str, results: &[SeedResult]) -> Result<()> {
    let mut families: Vec<&str> = Vec::new();
    for r in results {
        if !families.contains(&r.family.as_str()) {
            families.push(&r.family);
        }
    }
    let n = families.len().max(1) as f64;
    let panels = [
        ("mIoU (%)", "miou"),
        ("reflection removal (%)", "reflection_removal"),
    ];
    render(path, (1400, 650), |root| {
        root.titled(title, ("sans-serif", 24))
            .map_err(|e| plot_err(path, e))?;
        let halves = root.margin(40, 5, 5, 5).split_evenly((1, 2));
        for (area, (desc, key)) in halves.iter().zip(panels) {
            let mut chart = ChartBuilder::on(area)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d(-0.5..n - 0.5, 0.0..100.0)
                .map_err(|e| plot_err(path, e))?;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(2 * families.len() + 1)
                .x_label_formatter(&|x| {
                    let i = x.round();
                    if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < families.len() {
                        families[i as usize].to_string()
                    } else {
                        String::new()
                    }
                })
                .x_label_style(("sans-serif", 12))
                .y_desc(desc)
                .axis_desc_style(("sans-serif", 18))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            for (i, f) in families.iter().enumerate() {
                let mut values: Vec<f64> = results
                    .iter()
                    .filter(|r| r.family == *f)
                    .map(|r| r.metric(key))
                    .filter(|v| v.is_finite())
                    .collect();
                values.sort_by(f64::total_cmp);
                if values.is_empty() {
                    continue;
                }
                let median = values[values.len() / 2];
                let x = i as f64;
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x - 0.3, 0.0), (x + 0.3, median)],
                        RGBColor(180, 200, 240).filled(),
                    )))
                    .map_err(|e| plot_err(path, e))?;
                let k = values.len().max(2) as f64 - 1.0;
                chart
                    .draw_series(values.iter().enumerate().map(|(j, v)| {
                        let dx = -0.2 + 0.4 * j as f64 / k;
                        Circle::new((x + dx, *v), 4, RGBColor(20, 60, 160).filled())
                    }))
                    .map_err(|e| plot_err(path, e))?;
            }
        }
        Ok(())
    })
}

/// Draw the reliability diagram of `report` into `path`: above, per bin of
/// predicted confidence, the share of points correct (a bar over the bin,
/// a dot at the bin's mean confidence) against the diagonal of perfect
/// calibration; below, the points per bin (log scale, the count written
/// over each bar).
pub fn reliability_png(path: &Path, title: &str, report: &ReliabilityReport) -> Result<()> {
    let fmt = |v: f64| {
        if v.is_finite() {
            format!("{v:.3}")
        } else {
            "–".into()
        }
    };
    let caption = format!(
        "{} points, expected calibration error {}, confidence >= 0.9: {} points, accuracy {}",
        report.points,
        fmt(report.ece),
        report.confident_points,
        fmt(report.confident_accuracy)
    );
    render(path, (900, 1000), |root| {
        root.titled(title, ("sans-serif", 20))
            .map_err(|e| plot_err(path, e))?;
        let (top, bottom) = root.margin(30, 5, 5, 5).split_vertically(700);
        let mut chart = ChartBuilder::on(&top)
            .caption(&caption, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_labels(11)
            .y_labels(11)
            .x_desc("predicted confidence")
            .y_desc("measured accuracy")
            .axis_desc_style(("sans-serif", 18))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(report.bins.iter().filter(|b| b.points > 0).map(|b| {
                Rectangle::new(
                    [(b.lower + 0.005, 0.0), (b.upper - 0.005, b.accuracy)],
                    RGBColor(180, 200, 240).filled(),
                )
            }))
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(LineSeries::new(
                [(0.0, 0.0), (1.0, 1.0)],
                RGBColor(120, 120, 120).stroke_width(2),
            ))
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(report.bins.iter().filter(|b| b.points > 0).map(|b| {
                Circle::new(
                    (b.mean_confidence, b.accuracy),
                    6,
                    RGBColor(20, 60, 160).filled(),
                )
            }))
            .map_err(|e| plot_err(path, e))?;

        let most = report
            .bins
            .iter()
            .map(|b| b.points)
            .max()
            .unwrap_or(0)
            .max(1);
        let top_log = (most as f64).log10().ceil().max(1.0) + 0.5;
        let mut counts = ChartBuilder::on(&bottom)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, 0.0..top_log)
            .map_err(|e| plot_err(path, e))?;
        counts
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(11)
            .y_labels(top_log as usize + 1)
            .y_label_formatter(&|v| {
                if (v - v.round()).abs() < 1e-9 {
                    format!("1e{v:.0}")
                } else {
                    String::new()
                }
            })
            .x_desc("predicted confidence")
            .y_desc("points")
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let height = |n: u64| (n as f64).max(1.0).log10();
        counts
            .draw_series(report.bins.iter().filter(|b| b.points > 0).map(|b| {
                Rectangle::new(
                    [(b.lower + 0.005, 0.0), (b.upper - 0.005, height(b.points))],
                    RGBColor(150, 150, 150).filled(),
                )
            }))
            .map_err(|e| plot_err(path, e))?;
        counts
            .draw_series(report.bins.iter().filter(|b| b.points > 0).map(|b| {
                Text::new(
                    b.points.to_string(),
                    (b.lower + 0.01, height(b.points) + 0.1),
                    ("sans-serif", 13),
                )
            }))
            .map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classify::Class;
    use crate::eval::Reliability;

    /// The diagram is drawn for a report with points, and for one without
    /// (a method that gives no confidence).
    #[test]
    fn the_reliability_diagram_is_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = Reliability::default();
        for i in 0..1000 {
            let class = if i % 10 < 7 {
                Class::Normal
            } else {
                Class::Glass
            };
            r.add_point(1, class, 0.75);
            r.add_point(5, Class::Reflection, 1.0);
        }
        r.add_point(2, Class::Glass, 0.15);
        for (name, report) in [
            ("some", r.report()),
            ("none", Reliability::default().report()),
        ] {
            let path = dir.path().join(format!("{name}.png"));
            reliability_png(&path, "test", &report).unwrap();
            let b = std::fs::read(&path).unwrap();
            assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{name}");
            assert!(b.len() > 5_000, "{name}: {} bytes", b.len());
        }
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            2,
            "no temporary files"
        );
    }
}
