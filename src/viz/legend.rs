//! Legends drawn in a panel of their own, beside the chart: a legend inside
//! the data area covers data (the top-down map's used to hide the corner
//! of the room under it).

use std::path::Path;

use plotters::prelude::*;

use crate::{Error, Result};

/// A pixel rectangle of an image: `x0..x1` by `y0..y1` (half-open).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    /// Left edge.
    pub x0: i32,
    /// Top edge.
    pub y0: i32,
    /// One past the right edge.
    pub x1: i32,
    /// One past the bottom edge.
    pub y1: i32,
}

impl PixelRect {
    /// The rectangle of a drawing area.
    pub(crate) fn of<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>) -> Self {
        let (x, y) = area.get_pixel_range();
        Self {
            x0: x.start,
            y0: y.start,
            x1: x.end,
            y1: y.end,
        }
    }

    /// Whether the two rectangles share a pixel.
    pub fn intersects(&self, other: &Self) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }

    /// Whether the pixel `(x, y)` lies inside.
    pub fn contains(&self, x: i32, y: i32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

/// The mark of a legend entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// A filled dot (points).
    Dot([u8; 3]),
    /// A line of this width in pixels.
    Line([u8; 3], u32),
}

/// One legend entry: its mark and label.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LegendEntry {
    /// What the entry's data looks like.
    pub mark: Mark,
    /// The label.
    pub label: String,
}

/// Draw `entries` as a framed legend at the top of `area` (a panel beside
/// the chart) with labels of `font` pixels; returns the frame drawn.
pub(crate) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[LegendEntry],
    font: u32,
    path: &std::path::Path,
) -> Result<PixelRect>
where
    DB::ErrorType: 'static,
{
    let panel = PixelRect::of(area);
    let line = font as i32 + 8;
    let pad = 10;
    let frame = PixelRect {
        x0: pad,
        y0: 60,
        x1: (panel.x1 - panel.x0) - pad,
        y1: 60 + 2 * pad + line * entries.len() as i32,
    };
    area.draw(&Rectangle::new(
        [(frame.x0, frame.y0), (frame.x1 - 1, frame.y1 - 1)],
        BLACK.stroke_width(1),
    ))
    .map_err(|e| plot_err(path, e))?;
    let style = ("sans-serif", font).into_font().color(&BLACK);
    for (k, entry) in entries.iter().enumerate() {
        let y = frame.y0 + pad + line * k as i32 + line / 2;
        let x = frame.x0 + pad;
        match entry.mark {
            Mark::Dot(c) => area.draw(&Circle::new((x + 9, y), 5, rgb(c).filled())),
            Mark::Line(c, width) => area.draw(&PathElement::new(
                vec![(x, y), (x + 18, y)],
                rgb(c).stroke_width(width.max(2)),
            )),
        }
        .map_err(|e| plot_err(path, e))?;
        area.draw(&Text::new(
            entry.label.clone(),
            (x + 28, y - font as i32 / 2 - 1),
            style.clone(),
        ))
        .map_err(|e| plot_err(path, e))?;
    }
    // In image coordinates.
    Ok(PixelRect {
        x0: panel.x0 + frame.x0,
        y0: panel.y0 + frame.y0,
        x1: panel.x0 + frame.x1,
        y1: panel.y0 + frame.y1,
    })
}

/// A drawing error as the library's error, naming the plot's file.
pub(crate) fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Input(format!("{}: cannot draw the plot: {e}", path.display()))
}

/// A colour as `[r, g, b]` in plotters' type.
pub(crate) fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}
