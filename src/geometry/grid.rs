//! A raster of evidence counts in a plane chart: where a plane is known to
//! be transparent (beams pass it) or opaque (beams end on it).

use nalgebra::Point2;

/// What the evidence says about one spot of a plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// Beams pass through or reflect off it: glass or mirror.
    Transparent,
    /// Beams end on it with nothing behind: an ordinary surface.
    Opaque,
    /// Too little evidence either way.
    Unknown,
}

/// Transparent and opaque vote counts on a regular grid in a plane chart.
#[derive(Debug, Clone, PartialEq)]
pub struct EvidenceGrid {
    /// Chart coordinates of the lower-left corner of cell (0, 0).
    pub min: Point2<f64>,
    /// Cell edge length, m.
    pub cell: f64,
    /// Cells along `u`.
    pub cols: usize,
    /// Cells along `v`.
    pub rows: usize,
    /// Transparent votes per cell (row-major).
    pub transparent: Vec<u32>,
    /// Opaque votes per cell (row-major).
    pub opaque: Vec<u32>,
    /// Votes needed (over a cell and its 8 neighbours) to decide.
    pub min_votes: u32,
    /// Cell states computed by [`EvidenceGrid::finalize`] (empty before).
    states: Vec<Surface>,
}

impl EvidenceGrid {
    /// An empty grid covering `[min, max]` with cells of `cell` metres;
    /// `None` when the extent is degenerate or would exceed `max_cells`.
    pub fn new(
        min: Point2<f64>,
        max: Point2<f64>,
        cell: f64,
        min_votes: u32,
        max_cells: usize,
    ) -> Option<Self> {
        if !(cell > 0.0) || !(max.x > min.x) || !(max.y > min.y) {
            return None;
        }
        let cols = ((max.x - min.x) / cell).ceil() as usize;
        let rows = ((max.y - min.y) / cell).ceil() as usize;
        if cols == 0 || rows == 0 || cols.saturating_mul(rows) > max_cells {
            return None;
        }
        Some(Self {
            min,
            cell,
            cols,
            rows,
            transparent: vec![0; cols * rows],
            opaque: vec![0; cols * rows],
            min_votes,
            states: Vec::new(),
        })
    }

    /// Flat index of the cell holding `uv`, if inside the grid.
    #[inline]
    pub fn index(&self, uv: &Point2<f64>) -> Option<usize> {
        let i = ((uv.x - self.min.x) / self.cell).floor();
        let j = ((uv.y - self.min.y) / self.cell).floor();
        if i >= 0.0 && j >= 0.0 && (i as usize) < self.cols && (j as usize) < self.rows {
            Some(j as usize * self.cols + i as usize)
        } else {
            None
        }
    }

    /// Centre of a cell in chart coordinates.
    pub fn centre(&self, index: usize) -> Point2<f64> {
        let (i, j) = (index % self.cols, index / self.cols);
        Point2::new(
            self.min.x + (i as f64 + 0.5) * self.cell,
            self.min.y + (j as f64 + 0.5) * self.cell,
        )
    }

    /// An empty grid with the same geometry and thresholds.
    pub fn empty_like(&self) -> Self {
        Self {
            transparent: vec![0; self.transparent.len()],
            opaque: vec![0; self.opaque.len()],
            states: Vec::new(),
            ..self.clone()
        }
    }

    /// Compute every cell's state once, so [`state`](Self::state) is a
    /// lookup. Votes added afterwards call for another `finalize`.
    pub fn finalize(&mut self) {
        self.states = (0..self.cols * self.rows)
            .map(|k| self.vote_state(k))
            .collect();
    }

    /// Add votes to the cell holding `uv` (ignored outside the grid).
    pub fn vote(&mut self, uv: &Point2<f64>, transparent: u32, opaque: u32) {
        if let Some(k) = self.index(uv) {
            self.transparent[k] += transparent;
            self.opaque[k] += opaque;
        }
    }

    /// Add another grid's votes (same geometry).
    pub fn add(&mut self, other: &EvidenceGrid) {
        for (a, b) in self.transparent.iter_mut().zip(&other.transparent) {
            *a += b;
        }
        for (a, b) in self.opaque.iter_mut().zip(&other.opaque) {
            *a += b;
        }
    }

    /// The state of cell `index`: the majority of the votes over the cell
    /// and its 8 neighbours, when there are at least `min_votes`.
    pub fn cell_state(&self, index: usize) -> Surface {
        match self.states.get(index) {
            Some(s) => *s,
            None => self.vote_state(index),
        }
    }

    fn vote_state(&self, index: usize) -> Surface {
        let (i, j) = ((index % self.cols) as isize, (index / self.cols) as isize);
        let (mut t, mut o) = (0u32, 0u32);
        for dj in -1..=1 {
            for di in -1..=1 {
                let (x, y) = (i + di, j + dj);
                if x >= 0 && y >= 0 && (x as usize) < self.cols && (y as usize) < self.rows {
                    let k = y as usize * self.cols + x as usize;
                    t += self.transparent[k];
                    o += self.opaque[k];
                }
            }
        }
        if t + o < self.min_votes {
            Surface::Unknown
        } else if t >= o {
            Surface::Transparent
        } else {
            Surface::Opaque
        }
    }

    /// The state at chart coordinates `uv` (Unknown outside the grid).
    pub fn state(&self, uv: &Point2<f64>) -> Surface {
        self.index(uv)
            .map_or(Surface::Unknown, |k| self.cell_state(k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn majority_of_the_neighbourhood_decides() {
        let mut g =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), 0.1, 3, 1000).unwrap();
        assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Unknown);
        g.vote(&Point2::new(0.55, 0.55), 2, 0);
        g.vote(&Point2::new(0.45, 0.55), 0, 1);
        assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Transparent);
        g.vote(&Point2::new(0.65, 0.65), 0, 2);
        assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Opaque);
        assert_eq!(g.state(&Point2::new(5.0, 5.0)), Surface::Unknown);
        assert!(
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1e4, 1e4), 0.01, 1, 1000)
                .is_none()
        );
    }
}
