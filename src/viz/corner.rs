//! The "mapping around the corner" figure: the same classified map twice,
//! top-down, with the reflections where the sensor measured them (virtual
//! points behind the mirror) and after mirror-back (on the real objects).

use std::path::Path;

use plotters::prelude::*;

use super::plots::{
    equal_ranges, plane_outlines, plot_err, render, rgb, top_view_chart, trajectory_and_legend,
    TopView,
};

/// Sizes of the figure's two panels.
const PANEL: TopView = TopView {
    caption: 24,
    margin: 12,
    y_label_area: 50,
    labels: 15,
    axis_desc: 16,
    light_grid: false,
};
use crate::classify::Class;
use crate::io::map_ply::class_colour;
use crate::io::MapPoint;
use crate::reflect::BoundedPlane;
use crate::Result;

/// Most points drawn per panel (a regular subsample beyond).
const MAX_POINTS: usize = 150_000;

/// Draw `path`: two top-down panels sharing their axes, `before` (reflections
/// as measured) and `after` (reflections mirrored back), each with the
/// reflective planes' outlines and the trajectory.
pub fn around_corner_png(
    path: &Path,
    before: &[MapPoint],
    after: &[MapPoint],
    planes: &[BoundedPlane],
    trajectory: &[[f64; 2]],
) -> Result<()> {
    let (w, h) = (2000u32, 950u32);
    let xy = |p: &MapPoint| [f64::from(p.xyz[0]), f64::from(p.xyz[1])];
    let (xr, yr) = equal_ranges(
        before
            .iter()
            .chain(after)
            .map(xy)
            .chain(trajectory.iter().copied()),
        1.0,
        f64::from(w / 2 - 80),
        f64::from(h - 120),
    );
    let panels = [
        (
            "Reflections as measured (virtual, behind the mirror)",
            before,
        ),
        ("Reflections mirrored back (around the corner)", after),
    ];
    render(path, (w, h), |root| {
        for (area, (title, points)) in root.split_evenly((1, 2)).iter().zip(panels) {
            let mut chart = top_view_chart(area, title, (xr.clone(), yr.clone()), &PANEL, path)?;
            let step = points.len().div_ceil(MAX_POINTS).max(1);
            for (class, mirrored, name, size) in [
                (Class::Normal, false, "normal", 1),
                (Class::Obstacle, false, "obstacle behind glass", 1),
                (Class::Glass, false, "reflective surface", 1),
                (Class::Reflection, false, "reflection, measured", 2),
                (Class::Reflection, true, "reflection, mirrored back", 2),
            ] {
                let colour = rgb(class_colour(class, mirrored));
                let drawn: Vec<_> = points
                    .iter()
                    .step_by(step)
                    .filter(|p| p.class == class && p.mirrored == mirrored)
                    .map(|p| Circle::new((xy(p)[0], xy(p)[1]), size, colour.filled()))
                    .collect();
                if drawn.is_empty() {
                    continue;
                }
                chart
                    .draw_series(drawn)
                    .map_err(|e| plot_err(path, e))?
                    .label(name)
                    .legend(move |(x, y)| Circle::new((x + 8, y), 4, colour.filled()));
            }
            let mut labelled = false;
            for (_, line) in plane_outlines(planes) {
                let colour = RGBColor(170, 0, 200);
                let series = chart
                    .draw_series(LineSeries::new(line, colour.stroke_width(4)))
                    .map_err(|e| plot_err(path, e))?;
                if !labelled {
                    labelled = true;
                    series.label("mirror / glass plane").legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(3))
                    });
                }
            }
            trajectory_and_legend(&mut chart, trajectory, 16, path)?;
        }
        Ok(())
    })
}
