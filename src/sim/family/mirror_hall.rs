//! Halls with mirrors at any angle to the path: a hall with a side hall
//! opening off it, a mirror on a chamfered corner, wall mirrors seen from
//! far and at grazing angles, mirror-clad columns, and a glazed section of
//! wall onto a room or the street (so that glass is there too).

use glam::DVec2;

use super::draft::{Draft, GlassStyle, Glazing};
use super::SceneFamily;

/// Halls with mirrors at any angle.
pub struct MirrorHall;

impl SceneFamily for MirrorHall {
    fn name(&self) -> &'static str {
        "mirror-hall"
    }

    fn description(&self) -> &'static str {
        "a hall and a side hall with mirrors at any angle: chamfered corners, wall mirrors seen from far and grazing, mirror-clad columns"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let w = d.uniform(8.0, 18.0);
        let depth = d.uniform(6.0, 12.0);
        let h = d.uniform(2.7, 4.0);
        let plaster = d.diffuse("wall", 0.45, 0.85);
        let floor = d.diffuse("floor", 0.15, 0.5);
        let ceiling = d.diffuse("ceiling", 0.6, 0.85);
        let frame = d.diffuse("frame", 0.15, 0.5);
        let mirror = d.mirror();
        // The corner at (w, depth) is chamfered, at 25-65 degrees.
        let cx = d.uniform(1.2, 3.5);
        let cy = cx * d.uniform(0.5, 2.0).min((depth / 3.0) / cx);
        let chamfer = [DVec2::new(w - cx, depth), DVec2::new(w, depth - cy)];
        // The side hall opens off the east wall below the chamfer.
        let gap = d.uniform(1.6, 4.0).min(depth - cy - 1.0);
        let g0 = d.uniform(0.5, (depth - cy - gap - 0.5).max(0.5));
        let g1 = g0 + gap;
        let side_len = d.uniform(4.0, 10.0);
        let s0 = d.uniform(0.0, g0);
        let s1 = g1 + d.uniform(0.0, depth - cy - g1);
        let outline = [
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, g0),
            DVec2::new(w, g1),
            chamfer[1],
            chamfer[0],
            DVec2::new(0.0, depth),
        ];
        let west_glass = d.chance(0.6);
        let walls = [
            Some(plaster.as_str()),
            Some(plaster.as_str()),
            None,
            Some(plaster.as_str()),
            Some(plaster.as_str()),
            Some(plaster.as_str()),
            if west_glass {
                None
            } else {
                Some(plaster.as_str())
            },
        ];
        d.outline(&outline, &walls, h, &floor, &ceiling);
        d.wall(outline[2], outline[3], 2.2, h - 2.2, &plaster);
        // The side hall.
        let side = [
            DVec2::new(w, s0),
            DVec2::new(w + side_len, s0),
            DVec2::new(w + side_len, s1),
            DVec2::new(w, s1),
        ];
        d.outline(
            &side,
            &[Some(&plaster), Some(&plaster), Some(&plaster), None],
            h,
            &floor,
            &ceiling,
        );
        let inside = DVec2::new(w / 2.0, depth / 2.0);
        // Mirrors: the chamfer always; the others by chance.
        let base = d.uniform(0.0, 0.4);
        let height = d.uniform(1.8, 2.5).min(h - 0.1);
        d.panel(
            chamfer[1], chamfer[0], 0.0, 1.0, base, height, inside, &mirror,
        );
        if d.chance(0.5) {
            let a = d.uniform(0.05, 0.5);
            let b = a + d.uniform(0.15, 0.45);
            let base = d.uniform(0.0, 0.5);
            let height = d.uniform(1.5, 2.2);
            d.panel(outline[6], outline[5], a, b, base, height, inside, &mirror);
        }
        if d.chance(0.4) {
            // A long mirror along the path: seen at grazing angles.
            let base = d.uniform(0.0, 0.3);
            let height = d.uniform(1.8, 2.4).min(h - 0.1);
            d.panel(
                outline[0], outline[1], 0.1, 0.9, base, height, inside, &mirror,
            );
        }
        if d.chance(0.5) {
            // At the far end of the side hall: seen from far.
            let m = d.mirror();
            let base = d.uniform(0.0, 0.5);
            let height = d.uniform(1.5, 2.3).min(h - 0.1);
            d.panel(side[1], side[2], 0.1, 0.9, base, height, side[0], &m);
        }
        // Glass: a glazed section of the west wall onto a room or a street.
        if west_glass {
            let glass = d.glass(GlassStyle::Clear);
            let a = d.uniform(0.5, depth / 2.0);
            let b = a + d.uniform(1.5, depth / 2.0 - 0.5);
            d.wall(outline[6], DVec2::new(0.0, b), 0.0, h, &plaster);
            d.wall(DVec2::new(0.0, a), DVec2::ZERO, 0.0, h, &plaster);
            d.random_glazing(
                DVec2::new(0.0, b),
                DVec2::new(0.0, a),
                h,
                1.0,
                &glass,
                &frame,
            );
            let room = d.uniform(3.0, 7.0);
            let corners = [
                DVec2::new(-room, 0.0),
                DVec2::ZERO,
                DVec2::new(0.0, depth),
                DVec2::new(-room, depth),
            ];
            d.outline(
                &corners,
                &[Some(&plaster), None, Some(&plaster), Some(&plaster)],
                h,
                &floor,
                &ceiling,
            );
            let count = d.int(2, 5);
            d.clutter(corners[0] + 0.1, corners[2] - 0.1, 0.0, count);
        } else {
            // A glass door in the south wall onto the street.
            let glass = d.glass(GlassStyle::Clear);
            let at = d.uniform(0.5, w - 2.5);
            d.glazing(
                DVec2::new(at, 0.0),
                DVec2::new(at + 1.8, 0.0),
                0.0,
                &Glazing {
                    sill: 0.0,
                    head: 2.2,
                    top: 2.2,
                    pane: 0.9,
                    mullion: 0.06,
                    glass: &glass,
                    frame: &frame,
                },
            );
            let keep = (DVec2::ZERO, DVec2::new(w + side_len, depth));
            d.street(
                DVec2::new(-10.0, -25.0),
                DVec2::new(w + 10.0, 0.0),
                0.0,
                keep,
            );
        }
        // The path: from the hall into the side hall, and back; or a loop.
        let gm = (g0 + g1) / 2.0;
        if d.chance(0.7) {
            let start = DVec2::new(1.2, d.uniform(1.2, depth - 1.2));
            let pts = [
                start,
                DVec2::new(w - 1.2, gm),
                DVec2::new(w + 1.2, gm),
                DVec2::new(w + side_len - 1.2, (s0 + s1) / 2.0),
            ];
            d.path(&pts, false, 0.0);
        } else {
            let m = d.uniform(1.2, 2.0).min(depth / 3.0);
            d.loop_around(
                DVec2::splat(m),
                DVec2::new(w - m - cx.min(1.0), depth - m - cy.min(1.0)),
                0.0,
            );
        }
        if d.chance(0.4) {
            let s = d.uniform(0.5, 1.0);
            let at = DVec2::new(d.uniform(2.0, w - 2.0 - s), d.uniform(1.5, depth - 1.5 - s));
            let _ = d.solid(at.extend(0.0), (at + DVec2::splat(s)).extend(h), &mirror);
        }
        let n = (w * depth / 8.0) as usize;
        d.clutter(
            DVec2::splat(0.1),
            DVec2::new(w - cx - 0.1, depth - 0.1),
            0.0,
            n,
        );
        let count = d.int(1, 5);
        d.clutter(side[0] + 0.1, side[2] - 0.1, 0.0, count);
        Ok(())
    }
}
