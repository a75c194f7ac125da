//! Glass behind glass: an open-plan floor with glass-walled meeting rooms
//! (so a beam may cross two or more panes) and, half of the time, a double
//! facade of two glass layers with a cavity between them.

use glam::DVec2;

use super::draft::{Draft, GlassStyle};
use super::SceneFamily;

/// Glass behind glass.
pub struct GlassInGlass;

impl SceneFamily for GlassInGlass {
    fn name(&self) -> &'static str {
        "glass-in-glass"
    }

    fn description(&self) -> &'static str {
        "glass-walled meeting rooms in an open-plan floor and double facades: glass behind glass"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let w = d.uniform(12.0, 24.0);
        let depth = d.uniform(10.0, 18.0);
        let h = d.uniform(2.8, 3.6);
        let plaster = d.diffuse("wall", 0.45, 0.85);
        let floor = d.diffuse("floor", 0.15, 0.5);
        let ceiling = d.diffuse("ceiling", 0.6, 0.85);
        let frame = d.diffuse("frame", 0.15, 0.5);
        let corners = [
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, depth),
            DVec2::new(0.0, depth),
        ];
        d.outline(
            &corners,
            &[None, Some(&plaster), Some(&plaster), Some(&plaster)],
            h,
            &floor,
            &ceiling,
        );
        let inner = d.glass(GlassStyle::Clear);
        d.random_glazing(corners[0], corners[1], h, 0.9, &inner, &frame);
        let mut outside = 0.0;
        if d.chance(0.5) {
            // A double facade: a second glass layer and the cavity.
            let gap = d.uniform(0.3, 1.2);
            let outer = d.glass(GlassStyle::Clear);
            d.random_glazing(
                DVec2::new(0.0, -gap),
                DVec2::new(w, -gap),
                h,
                0.3,
                &outer,
                &frame,
            );
            d.floor_rect(DVec2::new(0.0, -gap), DVec2::new(w, 0.0), 0.0, &floor);
            d.ceiling_rect(DVec2::new(0.0, -gap), DVec2::new(w, 0.0), h, &ceiling);
            d.wall(
                DVec2::new(0.0, 0.0),
                DVec2::new(0.0, -gap),
                0.0,
                h,
                &plaster,
            );
            d.wall(DVec2::new(w, -gap), DVec2::new(w, 0.0), 0.0, h, &plaster);
            outside = -gap;
        }
        let ground = if d.chance(0.5) {
            0.0
        } else {
            -d.uniform(3.0, 10.0)
        };
        let keep = (DVec2::new(0.0, outside), DVec2::new(w, depth));
        d.street(
            DVec2::new(-10.0, -25.0),
            DVec2::new(w + 10.0, outside),
            ground,
            keep,
        );
        // The path: a loop around the meeting rooms.
        let m = d.uniform(1.3, 2.2);
        let (lo, hi) = (DVec2::splat(m), DVec2::new(w - m, depth - m));
        d.loop_around(lo, hi, 0.0);
        // One or two glass-walled rooms inside the loop.
        let (ilo, ihi) = (lo + 1.0, hi - 1.0);
        let span = ihi - ilo;
        if span.x < 3.0 || span.y < 2.5 {
            return Err("the floor is too small for a meeting room".into());
        }
        let rooms = if span.x > 8.0 { 2 } else { 1 };
        let cell = span.x / rooms as f64;
        for k in 0..rooms {
            let rw = d.uniform(3.0, (cell - 0.5).clamp(3.0, 6.0));
            let rd = d.uniform(2.5, span.y.min(4.5));
            let at = DVec2::new(
                ilo.x + cell * k as f64 + d.uniform(0.0, (cell - rw).max(0.0)),
                ilo.y + d.uniform(0.0, span.y - rd),
            );
            let r = [
                at,
                at + DVec2::new(rw, 0.0),
                at + DVec2::new(rw, rd),
                at + DVec2::new(0.0, rd),
            ];
            let glass = d.glass(GlassStyle::Clear);
            for i in 0..4 {
                if i == 0 || d.chance(0.7) {
                    d.random_glazing(r[i], r[(i + 1) % 4], h, 0.0, &glass, &frame);
                } else {
                    d.wall(r[i], r[(i + 1) % 4], 0.0, h, &plaster);
                }
            }
            let count = d.int(1, 4);
            d.clutter(r[0] + 0.1, r[2] - 0.1, 0.0, count);
            d.reserve((r[0] - 0.05).extend(0.0), (r[2] + 0.05).extend(h));
        }
        let n = (w * depth / 8.0) as usize;
        d.clutter(DVec2::splat(0.1), DVec2::new(w - 0.1, depth - 0.1), 0.0, n);
        Ok(())
    }
}
