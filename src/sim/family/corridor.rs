//! Glass-lined corridors: offices on one or both sides behind mullioned
//! panes or opaque walls with glass doors (closed, or open), furnished and
//! occupied, with a glass door at the far end some of the time.

use glam::DVec2;

use super::draft::{Draft, GlassStyle, Glazing};
use super::SceneFamily;

/// Glass-lined corridors.
pub struct GlassCorridor;

impl SceneFamily for GlassCorridor {
    fn name(&self) -> &'static str {
        "glass-corridor"
    }

    fn description(&self) -> &'static str {
        "a corridor lined with offices behind mullioned panes or glass doors, open and closed"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let len = d.uniform(14.0, 30.0);
        let width = d.uniform(1.8, 3.5);
        let h = d.uniform(2.5, 3.2);
        let plaster = d.diffuse("wall", 0.45, 0.85);
        let floor = d.diffuse("floor", 0.15, 0.5);
        let ceiling = d.diffuse("ceiling", 0.6, 0.85);
        let frame = d.diffuse("frame", 0.15, 0.5);
        let glass = d.glass(GlassStyle::Clear);
        d.floor_rect(DVec2::ZERO, DVec2::new(len, width), 0.0, &floor);
        d.ceiling_rect(DVec2::ZERO, DVec2::new(len, width), h, &ceiling);
        // The ends: a wall, or a glass door into a hall beyond.
        d.wall(DVec2::new(0.0, width), DVec2::ZERO, 0.0, h, &plaster);
        let end = [DVec2::new(len, 0.0), DVec2::new(len, width)];
        if d.chance(0.35) {
            let door = d.glass(GlassStyle::Clear);
            d.glazing(
                end[0],
                end[1],
                0.0,
                &Glazing {
                    sill: 0.0,
                    head: 2.1,
                    top: h,
                    pane: width / 2.0,
                    mullion: 0.08,
                    glass: &door,
                    frame: &frame,
                },
            );
            let hall = d.uniform(4.0, 8.0);
            let corners = [
                DVec2::new(len, -2.0),
                DVec2::new(len + hall, -2.0),
                DVec2::new(len + hall, width + 2.0),
                DVec2::new(len, width + 2.0),
            ];
            d.outline(
                &corners,
                &[Some(&plaster), Some(&plaster), Some(&plaster), None],
                h,
                &floor,
                &ceiling,
            );
            d.wall(corners[3], end[1], 0.0, h, &plaster);
            d.wall(end[0], corners[0], 0.0, h, &plaster);
            d.clutter(corners[0] + 0.1, corners[2] - 0.1, 0.0, 4);
        } else {
            d.wall(end[0], end[1], 0.0, h, &plaster);
        }
        // The path first: along the corridor and back.
        let y = width / 2.0 + d.uniform(-0.15, 0.15) * (width - 1.8);
        d.path(&[DVec2::new(1.0, y), DVec2::new(len - 1.0, y)], false, 0.0);
        // Offices on one side or both.
        let both = d.chance(0.6);
        self.side(
            d, len, 0.0, -1.0, h, &glass, &frame, &plaster, &floor, &ceiling,
        );
        if both {
            let other = d.glass(GlassStyle::Clear);
            self.side(
                d, len, width, 1.0, h, &other, &frame, &plaster, &floor, &ceiling,
            );
        } else {
            d.wall(
                DVec2::new(0.0, width),
                DVec2::new(len, width),
                0.0,
                h,
                &plaster,
            );
        }
        Ok(())
    }
}

impl GlassCorridor {
    /// The offices along the corridor wall y = `y0`, extending towards
    /// `sign` (-1: y < y0).
    #[allow(clippy::too_many_arguments)]
    fn side(
        &self,
        d: &mut Draft,
        len: f64,
        y0: f64,
        sign: f64,
        h: f64,
        glass: &str,
        frame: &str,
        plaster: &str,
        floor: &str,
        ceiling: &str,
    ) {
        let depth = d.uniform(3.0, 6.0);
        let y1 = y0 + sign * depth;
        let mut x = 0.0;
        while x < len - 1e-6 {
            let mut w = d.uniform(3.0, 6.0);
            if len - x - w < 1.5 {
                w = len - x;
            }
            let (a, b) = (DVec2::new(x, y0), DVec2::new(x + w, y0));
            // The first office is glazed, the others by chance.
            if x == 0.0 || d.chance(0.6) {
                d.random_glazing(a, b, h, 1.0, glass, frame);
            } else {
                // An opaque front with a glass door, closed or open.
                let door = d.uniform(0.9, 1.2).min(w - 0.4);
                let at = d.uniform(0.2, w - door - 0.2);
                let (p, q) = (DVec2::new(x + at, y0), DVec2::new(x + at + door, y0));
                d.wall(a, p, 0.0, h, plaster);
                d.wall(q, b, 0.0, h, plaster);
                d.wall(p, q, 2.1, h - 2.1, plaster);
                if d.chance(0.6) {
                    d.wall(p, q, 0.0, 2.1, glass);
                }
            }
            // The office: back wall, side walls, floor, ceiling, contents.
            d.wall(DVec2::new(x, y1), DVec2::new(x + w, y1), 0.0, h, plaster);
            d.wall(DVec2::new(x, y0), DVec2::new(x, y1), 0.0, h, plaster);
            let (lo, hi) = (DVec2::new(x, y0.min(y1)), DVec2::new(x + w, y0.max(y1)));
            d.floor_rect(lo, hi, 0.0, floor);
            d.ceiling_rect(lo, hi, h, ceiling);
            let n = d.int(2, 5);
            d.clutter(lo + 0.1, hi - 0.1, 0.0, n);
            x += w;
        }
        d.wall(DVec2::new(x, y0), DVec2::new(x, y1), 0.0, h, plaster);
    }
}
