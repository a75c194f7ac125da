//! Panes: the separate reflective surfaces on one infinite plane.
//!
//! A window wall may carry several panes with wall between them; the
//! evidence grid shows them as separate regions of transparent cells. Each
//! connected region (8-connected) large enough to be a pane gets its own
//! convex boundary, fitted against the opaque cells around it by the
//! boundary LP ([`fit_boundary`]).

use std::time::{Duration, Instant};

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use super::boundary_fit::{fit_boundary, BoundaryFitParams};
use crate::geometry::grid::{EvidenceGrid, Surface};
use crate::geometry::ConvexPolygon;

/// Pane segmentation settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaneParams {
    /// Smallest pane kept, m².
    pub min_area: f64,
    /// Opaque cells within this distance of a pane's cells constrain its
    /// boundary, m.
    pub context: f64,
    /// The boundary LP's weights and solver: [`super::boundary_fit::FIT`]
    /// (no keys).
    #[serde(skip, default = "fit")]
    pub fit: BoundaryFitParams,
}

fn fit() -> BoundaryFitParams {
    super::boundary_fit::FIT
}

impl Default for PaneParams {
    /// `[map.panes]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("map.panes")
    }
}

/// One pane: its evidence cells and fitted boundary (chart coordinates).
#[derive(Debug, Clone, PartialEq)]
pub struct Pane {
    /// Indices of the grid's transparent cells that form the pane.
    pub cells: Vec<usize>,
    /// The fitted convex boundary.
    pub boundary: ConvexPolygon,
    /// Time the LP took.
    pub solve_time: Duration,
}

/// Split the transparent cells of `grid` into panes and fit a boundary to
/// each. Deterministic: panes are ordered by their first cell.
pub fn find_panes(grid: &EvidenceGrid, params: &PaneParams) -> Vec<Pane> {
    let n = grid.cols * grid.rows;
    let regions = grid.regions(Surface::Transparent);
    let cell_area = grid.cell * grid.cell;
    // Opaque cells bordering non-opaque ones: interior opaque cells are
    // excluded by convexity once the border is (and the LP stays small).
    let is_opaque = |x: isize, y: isize| {
        x < 0
            || y < 0
            || x as usize >= grid.cols
            || y as usize >= grid.rows
            || grid.cell_state(y as usize * grid.cols + x as usize) == Surface::Opaque
    };
    let opaque: Vec<usize> = (0..n)
        .filter(|&k| grid.cell_state(k) == Surface::Opaque)
        .filter(|&k| {
            let (i, j) = ((k % grid.cols) as isize, (k / grid.cols) as isize);
            !(is_opaque(i - 1, j)
                && is_opaque(i + 1, j)
                && is_opaque(i, j - 1)
                && is_opaque(i, j + 1))
        })
        .collect();
    regions
        .into_iter()
        .filter(|cells| cells.len() as f64 * cell_area >= params.min_area)
        .filter_map(|cells| {
            // Only the region's border cells constrain a convex boundary: the
            // interior lies in their hull. This keeps the LP small (about the
            // perimeter, not the area, in rows).
            let border = border_cells(grid, &cells);
            let inside: Vec<Point2<f64>> = border.iter().map(|&k| grid.centre(k)).collect();
            // Opaque (border) cells within `context` of the pane's border.
            let reach = (params.context / grid.cell).ceil() as isize;
            let mut near = vec![false; n];
            for &k in &border {
                let (i, j) = ((k % grid.cols) as isize, (k / grid.cols) as isize);
                for y in (j - reach).max(0)..=(j + reach).min(grid.rows as isize - 1) {
                    for x in (i - reach).max(0)..=(i + reach).min(grid.cols as isize - 1) {
                        near[y as usize * grid.cols + x as usize] = true;
                    }
                }
            }
            let outside: Vec<Point2<f64>> = opaque
                .iter()
                .filter(|&&k| near[k])
                .map(|&k| grid.centre(k))
                .collect();
            let start = Instant::now();
            let boundary = fit_boundary(&inside, &outside, grid.cell / 2.0, &params.fit)?;
            Some(Pane {
                cells,
                boundary,
                solve_time: start.elapsed(),
            })
        })
        .collect()
}

/// The cells of a region (sorted indices) with a 4-neighbour outside it.
fn border_cells(grid: &EvidenceGrid, cells: &[usize]) -> Vec<usize> {
    let member = |x: isize, y: isize| {
        x >= 0
            && y >= 0
            && (x as usize) < grid.cols
            && (y as usize) < grid.rows
            && cells
                .binary_search(&(y as usize * grid.cols + x as usize))
                .is_ok()
    };
    cells
        .iter()
        .copied()
        .filter(|&k| {
            let (i, j) = ((k % grid.cols) as isize, (k / grid.cols) as isize);
            !(member(i - 1, j) && member(i + 1, j) && member(i, j - 1) && member(i, j + 1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_panes_with_a_wall_strip_between_them_are_two() {
        let mut g = EvidenceGrid::new(
            Point2::new(-1.0, -1.0),
            Point2::new(7.0, 3.0),
            0.2,
            2,
            100_000,
        )
        .unwrap();
        for k in 0..g.cols * g.rows {
            let c = g.centre(k);
            let in_a = c.x > 0.0 && c.x < 2.5 && c.y > 0.0 && c.y < 2.0;
            let in_b = c.x > 3.5 && c.x < 6.0 && c.y > 0.0 && c.y < 2.0;
            if in_a || in_b {
                g.vote(&c, 2, 0);
                g.vote_echo(&c);
            } else {
                g.vote(&c, 0, 3);
            }
        }
        g.finalize();
        let panes = find_panes(&g, &PaneParams::default());
        assert_eq!(panes.len(), 2);
        // The wall strip x in (2.5, 3.5) is in neither pane.
        for p in &panes {
            assert!(!p.boundary.contains(&Point2::new(3.0, 1.0)));
            assert!(
                (p.boundary.area() - 5.0).abs() < 1.0,
                "area {}",
                p.boundary.area()
            );
        }
        assert!(panes[0].boundary.contains(&Point2::new(1.2, 1.0)));
        assert!(panes[1].boundary.contains(&Point2::new(4.8, 1.0)));
    }

    #[test]
    fn no_transparent_evidence_means_no_pane() {
        let mut g =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(2.0, 2.0), 0.2, 2, 1000).unwrap();
        g.vote(&Point2::new(1.0, 1.0), 0, 5);
        g.finalize();
        assert!(find_panes(&g, &PaneParams::default()).is_empty());
        let empty =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(2.0, 2.0), 0.2, 2, 1000).unwrap();
        assert!(find_panes(&empty, &PaneParams::default()).is_empty());
    }
}
