//! Offices with window walls: a room with one or two glazed walls onto the
//! street (at the same level, or storeys above it), desks, cabinets and
//! people, and sometimes a glazed partition into the next room.

use glam::DVec2;

use super::draft::{Draft, GlassStyle};
use super::SceneFamily;

/// Offices with window walls.
pub struct Office;

impl SceneFamily for Office {
    fn name(&self) -> &'static str {
        "office"
    }

    fn description(&self) -> &'static str {
        "an office with one or two window walls onto a street at the same level or storeys below, furniture and people"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        draw_window_room(d, GlassStyle::Clear, false)
    }
}

/// A room `w` x `depth` with a window wall along y = 0 (and, sometimes,
/// x = w), the street outside and, with `partition`, a glazed partition
/// along y = depth into a furnished neighbour room.
pub(super) fn draw_window_room(
    d: &mut Draft,
    style: GlassStyle,
    partition: bool,
) -> Result<(), String> {
    let w = d.uniform(6.0, 14.0);
    let depth = d.uniform(5.0, 10.0);
    let h = d.uniform(2.6, 3.4);
    let plaster = d.diffuse("wall", 0.45, 0.85);
    let floor = d.diffuse("floor", 0.15, 0.5);
    let ceiling = d.diffuse("ceiling", 0.6, 0.85);
    let frame = d.diffuse("frame", 0.15, 0.5);
    let glass = d.glass(style);
    let side_window = d.chance(0.4);
    let corners = [
        DVec2::ZERO,
        DVec2::new(w, 0.0),
        DVec2::new(w, depth),
        DVec2::new(0.0, depth),
    ];
    let back = if partition {
        None
    } else {
        Some(plaster.as_str())
    };
    let east = if side_window {
        None
    } else {
        Some(plaster.as_str())
    };
    d.outline(
        &corners,
        &[None, east, back, Some(plaster.as_str())],
        h,
        &floor,
        &ceiling,
    );
    d.random_glazing(corners[0], corners[1], h, 0.9, &glass, &frame);
    if side_window {
        d.random_glazing(corners[1], corners[2], h, 0.9, &glass, &frame);
    }
    if partition {
        // A glazed partition and the room behind it.
        let inner = d.glass(style);
        d.random_glazing(corners[3], corners[2], h, 1.0, &inner, &frame);
        let beyond = depth + d.uniform(3.0, 6.0);
        let next = [
            DVec2::new(0.0, depth),
            DVec2::new(w, depth),
            DVec2::new(w, beyond),
            DVec2::new(0.0, beyond),
        ];
        d.outline(
            &next,
            &[None, Some(&plaster), Some(&plaster), Some(&plaster)],
            h,
            &floor,
            &ceiling,
        );
    }
    // A mirror or a screen on the inner wall, some of the time.
    if d.chance(0.3) {
        let mirror = d.mirror();
        let a = d.uniform(0.1, 0.6);
        let b = a + d.uniform(0.1, 0.35);
        let base = d.uniform(0.0, 0.8);
        let height = d.uniform(1.2, 1.9);
        d.panel(
            corners[3],
            corners[0],
            a,
            b,
            base,
            height,
            DVec2::new(w / 2.0, depth / 2.0),
            &mirror,
        );
    }
    // Outside: at the floor's level, or storeys below.
    let ground = if d.chance(0.55) {
        0.0
    } else {
        -d.uniform(3.0, 12.0)
    };
    let keep = (DVec2::new(0.0, 0.0), DVec2::new(w, depth.max(1.0) + 8.0));
    d.street(
        DVec2::new(-15.0, -25.0),
        DVec2::new(w + 15.0, 0.0),
        ground,
        keep,
    );
    if side_window {
        d.street(
            DVec2::new(w, 0.0),
            DVec2::new(w + 25.0, depth + 10.0),
            ground,
            keep,
        );
    }
    // The path: a loop or a walk through the room.
    let m = d.uniform(1.0, 1.8).min(depth / 3.0);
    if d.chance(0.5) {
        d.loop_around(DVec2::new(m, m), DVec2::new(w - m, depth - m), 0.0);
    } else {
        let y = depth * d.uniform(0.3, 0.6);
        d.path(&[DVec2::new(m, y), DVec2::new(w - m, y)], false, 0.0);
    }
    let n = (w * depth / 5.0) as usize;
    d.clutter(DVec2::splat(0.1), DVec2::new(w - 0.1, depth - 0.1), 0.0, n);
    if partition {
        d.clutter(
            DVec2::new(0.1, depth + 0.1),
            DVec2::new(w - 0.1, depth + 3.0),
            0.0,
            4,
        );
    }
    if ground == 0.0 {
        // Passers-by and street furniture close to the window.
        let count = d.int(1, 4);
        d.clutter(
            DVec2::new(-5.0, -6.0),
            DVec2::new(w + 5.0, -0.3),
            0.0,
            count,
        );
    }
    Ok(())
}
