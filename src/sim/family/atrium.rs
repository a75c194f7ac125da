//! Lobbies and atria: a tall hall with one or two glass facades onto the
//! street (its floor continuing outside at the same level, or a terrace
//! lower), columns (some mirror-clad), a mezzanine with a glass railing.

use glam::{DVec2, DVec3};

use super::draft::{Draft, GlassStyle, Glazing};
use super::SceneFamily;

/// Lobbies and atria.
pub struct Atrium;

impl SceneFamily for Atrium {
    fn name(&self) -> &'static str {
        "atrium"
    }

    fn description(&self) -> &'static str {
        "a tall hall with glass facades, the floor continuing outside at the same level or lower, columns, a mezzanine with a glass railing"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let w = d.uniform(14.0, 30.0);
        let depth = d.uniform(10.0, 20.0);
        let h = d.uniform(4.5, 9.0);
        let stone = d.diffuse("floor", 0.2, 0.55);
        let plaster = d.diffuse("wall", 0.45, 0.85);
        let ceiling = d.diffuse("ceiling", 0.6, 0.85);
        let frame = d.diffuse("frame", 0.15, 0.5);
        let facade = d.glass(GlassStyle::Clear);
        let west_facade = d.chance(0.5);
        let corners = [
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, depth),
            DVec2::new(0.0, depth),
        ];
        let west = if west_facade {
            None
        } else {
            Some(plaster.as_str())
        };
        d.outline(
            &corners,
            &[None, Some(&plaster), Some(&plaster), west],
            h,
            &stone,
            &ceiling,
        );
        d.random_glazing(corners[0], corners[1], h, 0.3, &facade, &frame);
        let keep = (DVec2::ZERO, DVec2::new(w, depth));
        let ground = self.ground(d);
        d.street(
            DVec2::new(-10.0, -25.0),
            DVec2::new(w + 10.0, 0.0),
            ground,
            keep,
        );
        if west_facade {
            let other = d.glass(GlassStyle::Clear);
            d.random_glazing(corners[3], corners[0], h, 0.3, &other, &frame);
            let ground = self.ground(d);
            d.street(
                DVec2::new(-25.0, 0.0),
                DVec2::new(0.0, depth + 10.0),
                ground,
                keep,
            );
        }
        // The path: a loop around the middle of the hall.
        let m = d.uniform(2.0, 4.0);
        let (lo, hi) = (DVec2::splat(m), DVec2::new(w - m, depth - m));
        d.loop_around(lo, hi, 0.0);
        // Columns inside the loop, some clad in mirror.
        let mirror = d.mirror();
        let columns = d.int(1, 3);
        for _ in 0..columns {
            let s = d.uniform(0.5, 1.2);
            let room = hi - lo - DVec2::splat(2.0 + s);
            if room.x <= 0.0 || room.y <= 0.0 {
                break;
            }
            let at =
                lo + DVec2::splat(1.0) + DVec2::new(d.uniform(0.0, room.x), d.uniform(0.0, room.y));
            let clad = if d.chance(0.35) {
                mirror.as_str()
            } else {
                plaster.as_str()
            };
            d.fixed(at.extend(0.0), (at + DVec2::splat(s)).extend(h), clad, &[]);
        }
        // A mezzanine along the back wall with a glass railing.
        if d.chance(0.6) && h > 5.5 {
            let z = d.uniform(3.0, (h - 2.2).min(4.5));
            let deep = d.uniform(3.0, 6.0).min(depth - hi.y - 0.5).max(1.0);
            let edge = depth - deep;
            let slab = d.diffuse("slab", 0.3, 0.6);
            d.fixed(
                DVec3::new(0.0, edge, z - 0.25),
                DVec3::new(w, depth, z),
                &slab,
                &[("floor", &slab), ("ceiling", &slab)],
            );
            let railing = d.glass(GlassStyle::Clear);
            let steel = d.diffuse("steel", 0.3, 0.6);
            let posts = d.uniform(2.0, 5.0);
            d.glazing(
                DVec2::new(0.0, edge),
                DVec2::new(w, edge),
                z,
                &Glazing {
                    sill: 0.0,
                    head: 1.1,
                    top: 1.1,
                    pane: posts,
                    mullion: 0.08,
                    glass: &railing,
                    frame: &steel,
                },
            );
        }
        let n = (w * depth / 15.0) as usize;
        d.clutter(DVec2::splat(0.1), DVec2::new(w - 0.1, depth - 0.1), 0.0, n);
        if ground_is_level(d) {
            let count = d.int(1, 5);
            d.clutter(
                DVec2::new(-3.0, -6.0),
                DVec2::new(w + 3.0, -0.3),
                0.0,
                count,
            );
        }
        Ok(())
    }
}

impl Atrium {
    /// The ground outside a facade: the floor's level half of the time,
    /// else a terrace 0.5-3 m lower.
    fn ground(&self, d: &mut Draft) -> f64 {
        if d.chance(0.5) {
            0.0
        } else {
            -d.uniform(0.5, 3.0)
        }
    }
}

/// Whether the last street drawn lies at the floor's level.
fn ground_is_level(d: &Draft) -> bool {
    d.file.floors.iter().any(|f| f.z == 0.0)
}
