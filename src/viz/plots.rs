//! PNG plots drawn with `plotters` (bitmap backend, embedded DejaVu Sans font,
//! no system font libraries): the trajectories and the per-class scores,
//! and what every plot shares (the top-down map is in [`super::topdown`]).

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::legend::{draw_legend, LegendEntry, Mark, PixelRect};
pub(crate) use super::legend::{plot_err, rgb};
use crate::eval::Metrics;
use crate::{Error, Result};

/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// Width of the legend panel beside a trajectory plot, px.
const LEGEND_WIDTH: u32 = 280;

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is embedded and known to be valid; a failure only means
        // labels are not drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Draw into a temporary `*.tmp.png` next to `path` and rename it into place.
pub(crate) fn render(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let tmp: PathBuf = path.with_file_name(format!("{stem}.tmp.png"));
    let result = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        draw(&root)?;
        root.present().map_err(|e| plot_err(path, e))
    })();
    match result {
        Ok(()) => std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Ranges covering `points` with a margin (at least `min_span` metres),
/// stretched so one metre has the same length on both axes of a `w`×`h` plot
/// area.
pub(crate) fn equal_ranges(
    points: impl Iterator<Item = [f64; 2]>,
    min_span: f64,
    w: f64,
    h: f64,
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points.filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if !(lo[0] <= hi[0]) {
        return (-1.0..1.0, -1.0..1.0);
    }
    let (cx, cy) = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0);
    let mut sx = (hi[0] - lo[0]).max(min_span) * 1.1;
    let mut sy = (hi[1] - lo[1]).max(min_span) * 1.1;
    if sx / sy < w / h {
        sx = sy * w / h;
    } else {
        sy = sx * h / w;
    }
    (cx - sx / 2.0..cx + sx / 2.0, cy - sy / 2.0..cy + sy / 2.0)
}

/// One named path of a trajectory plot (x, y, world frame).
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectorySeries {
    /// Legend label, e.g. "estimated" or "ground truth".
    pub name: String,
    /// Line colour.
    pub colour: [u8; 3],
    /// Line width, px (a reference drawn wide and light stays visible
    /// under an estimate that follows it closely).
    pub width: u32,
    /// The positions in order.
    pub points: Vec<[f64; 2]>,
}

/// What a trajectory plot drew.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryDrawn {
    /// The chart's data area in image pixels.
    pub data_area: PixelRect,
    /// The legend's frame in image pixels (beside the chart).
    pub legend: PixelRect,
}

/// `trajectory.png`: named trajectories (x, y, world frame), e.g. estimated
/// and true, drawn in order (the first at the bottom); dots mark the
/// poses, a large dot each start; `caption` says what is compared. The
/// legend is beside the chart.
pub fn trajectory_png(
    path: &Path,
    caption: &str,
    series: &[TrajectorySeries],
) -> Result<TrajectoryDrawn> {
    let (w, h) = (1000 + LEGEND_WIDTH, 800u32);
    let (xr, yr) = equal_ranges(
        series.iter().flat_map(|s| s.points.iter().copied()),
        0.1,
        f64::from(w - LEGEND_WIDTH - 90),
        f64::from(h - 110),
    );
    let mut drawn = None;
    render(path, (w, h), |root| {
        let (chart_area, legend_area) = root.split_horizontally(w - LEGEND_WIDTH);
        let mut chart = top_view_chart(
            &chart_area,
            caption,
            (xr, yr),
            &TopView {
                light_grid: true,
                ..TopView::LARGE
            },
            path,
        )?;
        for s in series {
            let colour = rgb(s.colour);
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().map(|p| (p[0], p[1])),
                    colour.stroke_width(s.width),
                ))
                .map_err(|e| plot_err(path, e))?;
            chart
                .draw_series(
                    s.points
                        .iter()
                        .map(|p| Circle::new((p[0], p[1]), 2, colour.filled())),
                )
                .map_err(|e| plot_err(path, e))?;
            chart
                .draw_series(
                    s.points
                        .first()
                        .map(|p| Circle::new((p[0], p[1]), 6, colour.filled())),
                )
                .map_err(|e| plot_err(path, e))?;
        }
        let entries: Vec<LegendEntry> = series
            .iter()
            .map(|s| LegendEntry {
                mark: Mark::Line(s.colour, s.width),
                label: s.name.clone(),
            })
            .collect();
        let legend = draw_legend(&legend_area, &entries, 18, path)?;
        drawn = Some(TrajectoryDrawn {
            data_area: PixelRect::of(&chart.plotting_area().strip_coord_spec()),
            legend,
        });
        Ok(())
    })?;
    drawn.ok_or_else(|| plot_err(path, "the drawing did not run"))
}

/// `metrics.png`: precision, recall and IoU (%) of every scored class as
/// grouped bars.
pub fn metrics_png(path: &Path, metrics: &Metrics) -> Result<()> {
    let classes = &metrics.classes;
    let n = classes.len() as f64;
    let names: Vec<String> = classes.iter().map(|c| c.class.name().to_string()).collect();
    let bars = [
        ("precision", RGBColor(30, 90, 255)),
        ("recall", RGBColor(240, 140, 0)),
        ("IoU", RGBColor(0, 160, 70)),
    ];
    render(path, (1000, 650), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "Per-class scores (accuracy {:.1} %, mIoU {:.1} %)",
                    metrics.accuracy, metrics.miou
                ),
                ("sans-serif", 26),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d(-0.5..n - 0.5, 0.0..130.0)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(2 * classes.len() + 1)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
                    names[i as usize].clone()
                } else {
                    String::new()
                }
            })
            .x_label_style(("sans-serif", 20))
            .y_desc("%")
            // Room above 100 % is for the legend: no ticks there.
            .y_label_formatter(&|y| {
                if *y <= 100.0 {
                    format!("{y:.0}")
                } else {
                    String::new()
                }
            })
            .y_label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (b, (name, colour)) in bars.iter().enumerate() {
            let colour = *colour;
            let rects = classes.iter().enumerate().map(|(i, c)| {
                let v = [c.precision, c.recall, c.iou][b];
                let v = if v.is_finite() { v } else { 0.0 };
                let x0 = i as f64 - 0.375 + b as f64 * 0.25;
                Rectangle::new([(x0, 0.0), (x0 + 0.23, v)], colour.filled())
            });
            chart
                .draw_series(rects)
                .map_err(|e| plot_err(path, e))?
                .label(*name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled())
                });
            let values = classes.iter().enumerate().map(|(i, c)| {
                let v = [c.precision, c.recall, c.iou][b];
                let v = if v.is_finite() { v } else { 0.0 };
                let x0 = i as f64 - 0.375 + b as f64 * 0.25;
                Text::new(format!("{v:.0}"), (x0 + 0.03, v + 5.0), ("sans-serif", 15))
            });
            chart.draw_series(values).map_err(|e| plot_err(path, e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 18))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| plot_err(path, e))
    })
}

/// Sizes of a top view in metres (x, y in the world frame).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TopView {
    /// Caption font, px.
    pub caption: u32,
    /// Margin around the chart, px.
    pub margin: u32,
    /// Width of the y label area, px.
    pub y_label_area: u32,
    /// Tick label font, px.
    pub labels: u32,
    /// Axis description font, px.
    pub axis_desc: u32,
    /// Draw the light grid lines between the bold ones.
    pub light_grid: bool,
}

impl TopView {
    /// The single-panel plots.
    pub const LARGE: Self = Self {
        caption: 26,
        margin: 15,
        y_label_area: 55,
        labels: 16,
        axis_desc: 18,
        light_grid: false,
    };

    /// The same with another caption size.
    pub const fn with_caption(self, caption: u32) -> Self {
        Self { caption, ..self }
    }
}

/// A captioned chart over `ranges` with metre axes and its mesh drawn:
/// the first layers of every top view.
pub(crate) fn top_view_chart<'a, DB: DrawingBackend + 'a>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    ranges: (std::ops::Range<f64>, std::ops::Range<f64>),
    style: &TopView,
    path: &Path,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", style.caption))
        .margin(style.margin)
        .x_label_area_size(40)
        .y_label_area_size(style.y_label_area)
        .build_cartesian_2d(ranges.0, ranges.1)
        .map_err(|e| plot_err(path, e))?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc("x [m]")
        .y_desc("y [m]")
        .label_style(("sans-serif", style.labels))
        .axis_desc_style(("sans-serif", style.axis_desc));
    if !style.light_grid {
        mesh.light_line_style(WHITE.mix(0.0));
    }
    mesh.draw().map_err(|e| plot_err(path, e))?;
    Ok(chart)
}
