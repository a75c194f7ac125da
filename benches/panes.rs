//! Solve time of the pane boundary LP (clarabel) for panes of several sizes.
//!
//! Run: `cargo bench --bench panes`. Each case is a rectangular pane of
//! transparent evidence cells (0.2 m) surrounded by a 1 m ring of opaque
//! cells, with 10% of the cells flipped as noise.

use std::time::Instant;

use nalgebra::Point2;
use specular::geometry::grid::EvidenceGrid;
use specular::map::{find_panes, PaneParams};
use specular::rng::SplitMix64;

fn grid(width: f64, height: f64, cell: f64, rng: &mut SplitMix64) -> EvidenceGrid {
    let mut g = EvidenceGrid::new(
        Point2::new(-1.0, -1.0),
        Point2::new(width + 1.0, height + 1.0),
        cell,
        2,
        10_000_000,
    )
    .expect("grid");
    for k in 0..g.cols * g.rows {
        let c = g.centre(k);
        let inside = c.x > 0.0 && c.x < width && c.y > 0.0 && c.y < height;
        let flip = rng.unit() < 0.1;
        if inside != flip {
            g.vote(&c, 3, 0);
            g.vote_echo(&c);
        } else {
            g.vote(&c, 0, 4);
        }
    }
    g.finalize();
    g
}

fn main() {
    let mut rng = SplitMix64::new(1);
    println!("pane size      cells  outside   solve ms (median of 9)  area m²");
    for (w, h) in [(1.0, 1.0), (2.0, 1.5), (4.0, 2.5), (8.0, 3.0), (12.0, 4.0)] {
        let g = grid(w, h, 0.2, &mut rng);
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..9 {
            let start = Instant::now();
            let panes = find_panes(&g, &PaneParams::default());
            times.push(start.elapsed().as_secs_f64() * 1e3);
            last = Some(panes);
        }
        times.sort_by(f64::total_cmp);
        let panes = last.unwrap_or_default();
        let biggest = panes.iter().max_by_key(|p| p.cells.len());
        let (cells, area) = biggest.map_or((0, 0.0), |p| (p.cells.len(), p.boundary.area()));
        let outside = g.opaque.iter().filter(|&&o| o > 0).count();
        println!(
            "{:>4.1} x {:<4.1}  {:>7}  {:>7}   {:>8.2}                {:>6.2}  ({} panes)",
            w,
            h,
            cells,
            outside,
            times[4],
            area,
            panes.len()
        );
    }
}
