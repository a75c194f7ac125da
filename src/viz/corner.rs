//! The "mapping around the corner" figure: the same classified map twice,
//! top-down, with the reflections where the sensor measured them (virtual
//! points behind the mirror) and after mirror-back (on the real objects).
//! Both panels draw [`corner_layers`] in order, the legend is beside them.

use std::path::Path;

use super::legend::{draw_legend, PixelRect};
use super::plots::{plot_err, render, TopView};
use super::topdown::{corner_layers, draw_panel, legend_entries, view_ranges, PanelDrawn};
use crate::io::MapPoint;
use crate::reflect::BoundedPlane;
use crate::Result;

/// Sizes of the figure's two panels.
const PANEL: TopView = TopView {
    caption: 24,
    margin: 12,
    y_label_area: 50,
    labels: 15,
    axis_desc: 16,
    light_grid: false,
};
/// Width of the legend panel, px.
const LEGEND_WIDTH: u32 = 300;

/// What the figure drew.
#[derive(Debug, Clone, PartialEq)]
pub struct CornerDrawn {
    /// The two panels: reflections as measured, then mirrored back.
    pub panels: [PanelDrawn; 2],
    /// The legend's frame in image pixels (beside the panels).
    pub legend: PixelRect,
}

/// Draw `path`: two top-down panels sharing their axes, `before` (reflections
/// as measured) and `after` (reflections mirrored back), each with the
/// reflective planes' outlines and the trajectory, and one legend beside
/// them.
pub fn around_corner_png(
    path: &Path,
    before: &[MapPoint],
    after: &[MapPoint],
    planes: &[BoundedPlane],
    trajectory: &[[f64; 2]],
) -> Result<CornerDrawn> {
    let (w, h) = (2000 + LEGEND_WIDTH, 950u32);
    let both: Vec<MapPoint> = before.iter().chain(after).copied().collect();
    let ranges = view_ranges(
        &both,
        planes,
        trajectory,
        f64::from(w / 2 - LEGEND_WIDTH / 2 - 80),
        f64::from(h - 120),
    );
    let titles = [
        "Reflections as measured (virtual, behind the mirror)",
        "Reflections mirrored back (around the corner)",
    ];
    let mut drawn = None;
    render(path, (w, h), |root| {
        let (charts, legend_area) = root.split_horizontally(w - LEGEND_WIDTH);
        let areas = charts.split_evenly((1, 2));
        let mut panels = Vec::with_capacity(2);
        for ((area, title), points) in areas.iter().zip(titles).zip([before, after]) {
            panels.push(draw_panel(
                area,
                title,
                ranges.clone(),
                &PANEL,
                corner_layers(),
                points,
                planes,
                trajectory,
                path,
            )?);
        }
        let entries = legend_entries(corner_layers(), &panels.iter().collect::<Vec<_>>());
        let legend = draw_legend(&legend_area, &entries, 16, path)?;
        drawn = Some((panels, legend));
        Ok(())
    })?;
    let (panels, legend) = drawn.ok_or_else(|| plot_err(path, "the drawing did not run"))?;
    let panels: [PanelDrawn; 2] = panels
        .try_into()
        .map_err(|_| plot_err(path, "two panels expected"))?;
    Ok(CornerDrawn { panels, legend })
}
