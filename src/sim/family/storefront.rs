//! Shop fronts and street facades: a row of shops with display windows and
//! glass doors along a street, seen from the pavement outside or from
//! inside a shop, with shelves and people inside, cars and trees outside.

use glam::DVec2;

use super::draft::{Draft, GlassStyle, Glazing};
use super::SceneFamily;

/// Shop fronts seen from inside and outside.
pub struct Storefront;

impl SceneFamily for Storefront {
    fn name(&self) -> &'static str {
        "storefront"
    }

    fn description(&self) -> &'static str {
        "shop fronts along a street, seen from the pavement or from inside a shop"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let plaster = d.diffuse("wall", 0.3, 0.8);
        let floor = d.diffuse("floor", 0.15, 0.5);
        let ceiling = d.diffuse("ceiling", 0.6, 0.85);
        let frame = d.diffuse("frame", 0.1, 0.5);
        let h = d.uniform(3.0, 4.5);
        let shops = d.int(2, 4);
        let mut xs = vec![0.0];
        for _ in 0..shops {
            let w = d.uniform(4.0, 10.0);
            xs.push(xs.last().copied().unwrap_or(0.0) + w);
        }
        let len = xs[shops];
        let depth: Vec<f64> = (0..shops).map(|_| d.uniform(5.0, 12.0)).collect();
        let pavement = d.uniform(3.0, 5.0);
        // The street in front (y < 0): pavement, road and the far side.
        let keep = (DVec2::new(0.0, 0.0), DVec2::new(len, 12.0));
        let far = -pavement - d.uniform(6.0, 12.0);
        d.street(
            DVec2::new(-10.0, far - 15.0),
            DVec2::new(len + 10.0, 0.0),
            0.0,
            keep,
        );
        // The storeys above the shops.
        let upper = d.uniform(3.0, 10.0);
        d.wall(DVec2::ZERO, DVec2::new(len, 0.0), h, upper, &plaster);
        for k in 0..shops {
            let (x0, x1) = (xs[k], xs[k + 1]);
            let glass = d.glass(GlassStyle::Clear);
            // Display windows with a glass door.
            let door = d.uniform(0.9, 1.8);
            let at = x0 + d.uniform(0.5, (x1 - x0) - door - 0.5);
            let windows = Glazing {
                sill: d.uniform(0.0, 0.8),
                head: h - 0.3,
                top: h,
                pane: d.uniform(1.2, 3.0),
                mullion: d.uniform(0.05, 0.2),
                glass: &glass,
                frame: &frame,
            };
            let entrance = Glazing {
                sill: 0.0,
                head: 2.2,
                pane: door,
                ..windows
            };
            let (p, q) = (DVec2::new(at, 0.0), DVec2::new(at + door, 0.0));
            d.glazing(DVec2::new(x0, 0.0), p, 0.0, &windows);
            d.glazing(p, q, 0.0, &entrance);
            d.glazing(q, DVec2::new(x1, 0.0), 0.0, &windows);
            let corners = [
                DVec2::new(x0, 0.0),
                DVec2::new(x1, 0.0),
                DVec2::new(x1, depth[k]),
                DVec2::new(x0, depth[k]),
            ];
            d.outline(
                &corners,
                &[None, Some(&plaster), Some(&plaster), Some(&plaster)],
                h,
                &floor,
                &ceiling,
            );
        }
        // The path: along the pavement, or inside one shop.
        if d.chance(0.6) {
            let y = -pavement * d.uniform(0.35, 0.65);
            d.path(&[DVec2::new(1.0, y), DVec2::new(len - 1.0, y)], false, 0.0);
        } else {
            let k = d.int(0, shops - 1);
            let m = d.uniform(1.0, 1.5);
            let (lo, hi) = (
                DVec2::new(xs[k] + m, m),
                DVec2::new(xs[k + 1] - m, depth[k] - m),
            );
            if d.chance(0.5) {
                d.loop_around(lo, hi, 0.0);
            } else {
                d.path(
                    &[DVec2::new(lo.x, lo.y), DVec2::new(hi.x, lo.y)],
                    false,
                    0.0,
                );
            }
        }
        for k in 0..shops {
            let n = ((xs[k + 1] - xs[k]) * depth[k] / 6.0) as usize;
            d.clutter(
                DVec2::new(xs[k] + 0.1, 0.1),
                DVec2::new(xs[k + 1] - 0.1, depth[k] - 0.1),
                0.0,
                n,
            );
        }
        // People on the pavement.
        let count = d.int(1, 5);
        d.clutter(
            DVec2::new(0.0, -pavement),
            DVec2::new(len, -0.2),
            0.0,
            count,
        );
        Ok(())
    }
}
