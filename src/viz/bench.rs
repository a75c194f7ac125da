//! `bench.png`: the benchmark's seeds per family, one dot a seed, for mIoU
//! and reflection removal side by side, the median as a bar, so a reader
//! sees the spread and the worst seed, not only a mean.

use std::path::Path;

use plotters::prelude::*;

use super::plots::{plot_err, render};
use crate::bench::SeedResult;
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
