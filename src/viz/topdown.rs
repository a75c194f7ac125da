//! The classified map seen from above, as people read it.
//!
//! - **A height slice.** Seen from above, the floor and the ceiling cover
//!   every room and hide the walls, the furniture and the glass; the view
//!   draws only the points between two heights above the floor
//!   ([`HeightSlice`], `[output] topdown_min_height` / `topdown_max_height`,
//!   0.3-2.0 m by default: above the floor, below the ceiling, across the
//!   windows and mirrors).
//! - **The floor** is fitted to the map itself ([`fit_floor`]): the
//!   near-horizontal plane holding the most Normal points below the sensor
//!   (why a plane, and not the ground landmark or a low percentile of the
//!   heights: [`super::floor`]).
//! - **An explicit drawing order** ([`Layer`], [`topdown_layers`]): the
//!   reflective surface is drawn over the panes' and hulls' outlines, which
//!   used to hide it exactly where it is.
//! - **The legend in a panel of its own** beside the chart, never over the
//!   data ([`super::legend`]).

use std::ops::Range;
use std::path::Path;

use plotters::prelude::*;

use super::floor::fit_floor;
use super::legend::{draw_legend, LegendEntry, Mark, PixelRect};
use super::plots::{equal_ranges, plot_err, render, rgb, top_view_chart, TopView};
use crate::classify::Class;
use crate::geometry::Plane;
use crate::io::map_ply::class_colour;
use crate::io::MapPoint;
use crate::reflect::BoundedPlane;
use crate::Result;

/// Most points drawn in one top view (a regular subsample beyond).
const MAX_DRAWN_POINTS: usize = 200_000;
/// Width of the legend panel, px.
const LEGEND_WIDTH: u32 = 300;
/// Colour of the reflective panes' outlines.
const PANE: [u8; 3] = [0, 190, 210];
/// Colour of the reflective planes' hulls.
const HULL: [u8; 3] = [170, 0, 200];
/// Colour of the sensor path.
const PATH: [u8; 3] = [0, 0, 0];

/// The heights drawn in a top view, metres above the floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightSlice {
    /// Lowest height drawn (`-inf`: no lower bound).
    pub min: f64,
    /// Highest height drawn (`inf`: no upper bound).
    pub max: f64,
}

impl HeightSlice {
    /// Every height: no slice.
    pub const ALL: Self = Self {
        min: f64::NEG_INFINITY,
        max: f64::INFINITY,
    };

    /// Whether the slice bounds anything.
    pub fn is_bounded(&self) -> bool {
        self.min.is_finite() || self.max.is_finite()
    }
}

/// One layer of a top view. Layers are drawn in the order of their list,
/// each over the ones before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// The points of one class; reflections where measured or, with
    /// `mirrored`, mirrored back to their objects.
    Points {
        /// The class drawn.
        class: Class,
        /// Reflections mirrored back (only meaningful for Reflection).
        mirrored: bool,
    },
    /// The hulls of the reflective planes that have no panes (with panes,
    /// the panes are the reflective extent and the hull is not used).
    Hulls,
    /// The reflective panes' outlines.
    Panes,
    /// The sensor path.
    Trajectory,
}

/// How pane (`true`) and hull outlines are drawn: colour and width, px. A
/// pane is a wide band, so that it shows on both sides of the reflective
/// surface's points drawn over it.
const fn outline_mark(pane: bool) -> Mark {
    if pane {
        Mark::Line(PANE, 9)
    } else {
        Mark::Line(HULL, 2)
    }
}

const fn points(class: Class) -> Layer {
    Layer::Points {
        class,
        mirrored: false,
    }
}

/// The drawing order of `topdown.png`: points under the outlines, except
/// the reflective surface, which lies on the panes and is drawn over them.
pub fn topdown_layers() -> &'static [Layer] {
    const LAYERS: [Layer; 7] = [
        points(Class::Normal),
        points(Class::Obstacle),
        points(Class::Reflection),
        Layer::Hulls,
        Layer::Panes,
        points(Class::Glass),
        Layer::Trajectory,
    ];
    &LAYERS
}

/// The drawing order of each panel of the around-the-corner figure: as
/// [`topdown_layers`], with the reflections mirrored back too.
pub fn corner_layers() -> &'static [Layer] {
    const LAYERS: [Layer; 8] = [
        points(Class::Normal),
        points(Class::Obstacle),
        points(Class::Reflection),
        Layer::Points {
            class: Class::Reflection,
            mirrored: true,
        },
        Layer::Hulls,
        Layer::Panes,
        points(Class::Glass),
        Layer::Trajectory,
    ];
    &LAYERS
}

impl Layer {
    /// The layer's legend entry.
    pub fn legend(&self) -> LegendEntry {
        let (mark, label) = match *self {
            Layer::Points { class, mirrored } => (
                Mark::Dot(class_colour(class, mirrored)),
                match (class, mirrored) {
                    (Class::Normal, _) => "normal",
                    (Class::Glass, _) => "reflective surface",
                    (Class::Obstacle, _) => "obstacle behind glass",
                    (Class::Reflection, false) => "reflection, measured",
                    (Class::Reflection, true) => "reflection, mirrored back",
                    (Class::Unclassified, _) => "unclassified",
                },
            ),
            Layer::Hulls => (outline_mark(false), "reflective plane hull"),
            Layer::Panes => (outline_mark(true), "reflective pane"),
            Layer::Trajectory => (Mark::Line(PATH, 2), "trajectory"),
        };
        LegendEntry {
            mark,
            label: label.to_string(),
        }
    }
}

/// What one top-view panel drew.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelDrawn {
    /// The layers in the order drawn, each with the number of items drawn
    /// (points, outlines, or 1 for the trajectory).
    pub layers: Vec<(Layer, usize)>,
    /// The chart's data area in image pixels.
    pub data_area: PixelRect,
    /// The x range shown, metres.
    pub x_range: Range<f64>,
    /// The y range shown, metres.
    pub y_range: Range<f64>,
}

impl PanelDrawn {
    /// The image pixel of world point `(x, y)` (about: the axes' rounding
    /// may move it by a pixel).
    pub fn pixel(&self, x: f64, y: f64) -> (i32, i32) {
        let a = &self.data_area;
        let fx = (x - self.x_range.start) / (self.x_range.end - self.x_range.start);
        let fy = (y - self.y_range.start) / (self.y_range.end - self.y_range.start);
        (
            a.x0 + (fx * f64::from(a.x1 - a.x0 - 1)).round() as i32,
            a.y1 - 1 - (fy * f64::from(a.y1 - a.y0 - 1)).round() as i32,
        )
    }

    /// The number of items drawn in `layer` (0 when not drawn).
    pub fn count(&self, layer: Layer) -> usize {
        self.layers
            .iter()
            .filter(|(l, _)| *l == layer)
            .map(|(_, n)| n)
            .sum()
    }
}

/// What `topdown.png` shows.
#[derive(Debug, Clone, PartialEq)]
pub struct TopdownDrawn {
    /// The floor (facing up: its signed distance is the height above it),
    /// when found ([`fit_floor`]).
    pub floor: Option<Plane>,
    /// The heights above the floor drawn (`None`: every point, e.g. no
    /// floor found).
    pub slice: Option<HeightSlice>,
    /// Map points left out as outside the slice.
    pub outside_slice: usize,
    /// The chart.
    pub panel: PanelDrawn,
    /// The legend's frame in image pixels (beside the chart).
    pub legend: PixelRect,
}

/// `topdown.png`: the classified map seen from above (points coloured by
/// class) cut to the heights of `slice` above the floor, the reflective
/// panes (cyan) and the hulls of the planes without panes (purple), the
/// trajectory (black; `trajectory` holds the sensor positions, x y z) and a
/// legend beside the chart. Returns what was drawn.
pub fn topdown_png(
    path: &Path,
    points: &[MapPoint],
    planes: &[BoundedPlane],
    trajectory: &[[f64; 3]],
    slice: HeightSlice,
) -> Result<TopdownDrawn> {
    let sensor: Vec<f64> = trajectory.iter().map(|p| p[2]).collect();
    let floor = if slice.is_bounded() {
        fit_floor(points, &sensor)
    } else {
        None
    };
    let shown: Vec<MapPoint> = match &floor {
        Some(f) => points
            .iter()
            .filter(|p| {
                let h = f.signed_distance(&nalgebra::Point3::from(p.xyz.map(f64::from)));
                slice.min <= h && h <= slice.max
            })
            .copied()
            .collect(),
        None => points.to_vec(),
    };
    let caption = match &floor {
        Some(f) => format!(
            "Classified map, top-down: {} above the floor (floor tilt {:.1}°)",
            slice_text(&slice),
            f.normal.z.clamp(-1.0, 1.0).acos().to_degrees()
        ),
        None => "Classified map, top-down (all heights)".to_string(),
    };
    let path2: Vec<[f64; 2]> = trajectory.iter().map(|p| [p[0], p[1]]).collect();
    let (w, h) = (1400 + LEGEND_WIDTH, 1100u32);
    let ranges = view_ranges(
        &shown,
        planes,
        &path2,
        f64::from(w - LEGEND_WIDTH - 90),
        990.0,
    );
    let mut drawn = None;
    render(path, (w, h), |root| {
        let (chart_area, legend_area) = root.split_horizontally(w - LEGEND_WIDTH);
        let panel = draw_panel(
            &chart_area,
            &caption,
            ranges,
            &TopView::LARGE.with_caption(26),
            topdown_layers(),
            &shown,
            planes,
            &path2,
            path,
        )?;
        let entries = legend_entries(topdown_layers(), &[&panel]);
        let legend = draw_legend(&legend_area, &entries, 18, path)?;
        drawn = Some((panel, legend));
        Ok(())
    })?;
    let (panel, legend) = drawn.ok_or_else(|| plot_err(path, "the drawing did not run"))?;
    Ok(TopdownDrawn {
        slice: floor.is_some().then_some(slice),
        floor,
        outside_slice: points.len() - shown.len(),
        panel,
        legend,
    })
}

/// "0.30-2.00 m" (or "above 0.30 m", "below 2.00 m").
fn slice_text(slice: &HeightSlice) -> String {
    match (slice.min.is_finite(), slice.max.is_finite()) {
        (true, true) => format!("{:.2}-{:.2} m", slice.min, slice.max),
        (true, false) => format!("above {:.2} m", slice.min),
        _ => format!("below {:.2} m", slice.max),
    }
}

/// The ranges of a top view of `points`, the drawn outlines of `planes` and
/// `trajectory` in a `w`×`h` px data area, one metre as long on both axes.
pub(crate) fn view_ranges(
    points: &[MapPoint],
    planes: &[BoundedPlane],
    trajectory: &[[f64; 2]],
    w: f64,
    h: f64,
) -> (Range<f64>, Range<f64>) {
    let outlines: Vec<[f64; 2]> = plane_outlines(planes)
        .into_iter()
        .flat_map(|(_, line)| line.into_iter().map(|(x, y)| [x, y]))
        .collect();
    equal_ranges(
        points
            .iter()
            .map(|p| [f64::from(p.xyz[0]), f64::from(p.xyz[1])])
            .chain(trajectory.iter().copied())
            .chain(outlines),
        1.0,
        w,
        h,
    )
}

/// The legend of `layers`: those that drew something in any of `panels`.
pub(crate) fn legend_entries(layers: &[Layer], panels: &[&PanelDrawn]) -> Vec<LegendEntry> {
    layers
        .iter()
        .filter(|&&l| panels.iter().any(|p| p.count(l) > 0))
        .map(Layer::legend)
        .collect()
}

/// The outlines drawn for `planes`, seen from above (x, y): each pane
/// (`true`), and the hull of each plane without panes (`false`).
pub(crate) fn plane_outlines(planes: &[BoundedPlane]) -> Vec<(bool, Vec<(f64, f64)>)> {
    let mut out = Vec::new();
    for bp in planes {
        let mut push = |vs: Vec<nalgebra::Point3<f64>>, pane: bool| {
            if let Some(line) = outline_from_above(&vs) {
                out.push((pane, line));
            }
        };
        match &bp.panes {
            Some(panes) => {
                for pane in panes.iter() {
                    push(
                        pane.vertices().iter().map(|q| bp.chart.to_3d(q)).collect(),
                        true,
                    );
                }
            }
            None => push(bp.boundary_3d(), false),
        }
    }
    out
}

/// A polygon (3-D vertices) seen from above: the closed outline of its
/// projection, or, for an upright polygon whose projection has no area
/// (a window seen from above is a segment), the segment between its two
/// farthest points (a wide line folded back on itself is not drawn as a
/// band). `None` without vertices.
fn outline_from_above(vs: &[nalgebra::Point3<f64>]) -> Option<Vec<(f64, f64)>> {
    let projected: Vec<nalgebra::Point2<f64>> =
        vs.iter().map(|p| nalgebra::Point2::new(p.x, p.y)).collect();
    let hull = crate::geometry::ConvexPolygon::hull(&projected);
    let corners = if hull.is_empty() {
        &projected[..]
    } else {
        hull.vertices()
    };
    let first = *corners.first()?;
    let mut span = (first, first, 0.0);
    for (k, a) in corners.iter().enumerate() {
        for b in &corners[k + 1..] {
            let d = (b - a).norm();
            if d > span.2 {
                span = (*a, *b, d);
            }
        }
    }
    // Thinner than 2 cm on average across its length: a segment.
    if hull.is_empty() || hull.area() < 0.02 * span.2 {
        return Some(vec![(span.0.x, span.0.y), (span.1.x, span.1.y)]);
    }
    let mut line: Vec<(f64, f64)> = corners.iter().map(|p| (p.x, p.y)).collect();
    line.push((first.x, first.y));
    Some(line)
}

/// Draw one top-view panel into `area`: caption, axes, then `layers` in
/// order (`points` already cut to what is shown). Returns what was drawn.
#[allow(clippy::too_many_arguments)]
pub(crate) fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    ranges: (Range<f64>, Range<f64>),
    style: &TopView,
    layers: &[Layer],
    points: &[MapPoint],
    planes: &[BoundedPlane],
    trajectory: &[[f64; 2]],
    path: &Path,
) -> Result<PanelDrawn>
where
    DB::ErrorType: 'static,
{
    let (x_range, y_range) = ranges.clone();
    let mut chart = top_view_chart(area, caption, ranges, style, path)?;
    let step = points.len().div_ceil(MAX_DRAWN_POINTS).max(1);
    let outlines = plane_outlines(planes);
    let mut drawn = Vec::with_capacity(layers.len());
    for &layer in layers {
        let count = match layer {
            Layer::Points { class, mirrored } => {
                let colour = rgb(class_colour(class, mirrored));
                // The reflective surface is thin: larger dots, over the panes.
                let size = if class == Class::Glass || mirrored {
                    2
                } else {
                    1
                };
                let dots: Vec<_> = points
                    .iter()
                    .step_by(step)
                    .filter(|p| p.class == class && p.mirrored == mirrored)
                    .map(|p| {
                        let (x, y) = (f64::from(p.xyz[0]), f64::from(p.xyz[1]));
                        Circle::new((x, y), size, colour.filled())
                    })
                    .collect();
                let n = dots.len();
                chart.draw_series(dots).map_err(|e| plot_err(path, e))?;
                n
            }
            Layer::Hulls | Layer::Panes => {
                let pane = layer == Layer::Panes;
                let (colour, width) = match outline_mark(pane) {
                    Mark::Line(c, w) => (c, w),
                    Mark::Dot(c) => (c, 2),
                };
                let mut n = 0;
                for (_, line) in outlines.iter().filter(|(p, _)| *p == pane) {
                    chart
                        .draw_series(LineSeries::new(
                            line.iter().copied(),
                            rgb(colour).stroke_width(width),
                        ))
                        .map_err(|e| plot_err(path, e))?;
                    n += 1;
                }
                n
            }
            Layer::Trajectory => {
                if trajectory.is_empty() {
                    0
                } else {
                    chart
                        .draw_series(LineSeries::new(
                            trajectory.iter().map(|p| (p[0], p[1])),
                            rgb(PATH).stroke_width(2),
                        ))
                        .map_err(|e| plot_err(path, e))?;
                    1
                }
            }
        };
        drawn.push((layer, count));
    }
    Ok(PanelDrawn {
        layers: drawn,
        data_area: PixelRect::of(&chart.plotting_area().strip_coord_spec()),
        x_range,
        y_range,
    })
}
