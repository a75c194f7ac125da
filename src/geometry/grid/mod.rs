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
    /// Beams pass it, but the region around it returns no surface echo: an
    /// opening (or the plane's extension into open space), not glass.
    Open,
    /// Too little evidence either way.
    Unknown,
}

/// Number of incidence bins ([`incidence_bin`]).
pub const INCIDENCE_BINS: usize = 9;

/// Width of the incidence bins in which echoes on a plane are compared
/// with its glass echoes, degrees: a glass echo's strength falls steeply
/// away from normal incidence (a specular peak and a faint diffuse lobe), a
/// wall's does not, so they are compared at the same incidence.
pub const INCIDENCE_BIN_DEG: f64 = 10.0;

/// The incidence bin of a beam meeting a plane at cosine `cos` (either
/// side), the last holding everything from 80 degrees on.
pub fn incidence_bin(cos: f64) -> u8 {
    let deg = cos.abs().clamp(0.0, 1.0).acos().to_degrees();
    (deg / INCIDENCE_BIN_DEG)
        .floor()
        .min((INCIDENCE_BINS - 1) as f64) as u8
}

/// The strength of an echo on a plane, `log10(I · r^k)`: the echo strength
/// of `reflect::echo_split` without its Lambertian incidence term (glass is
/// not Lambertian; echoes on a plane are compared within one incidence
/// bin).
pub fn strength_on_plane(intensity: f32, range: f64, range_exponent: f64) -> f64 {
    (intensity.max(0.5) as f64).log10() + range_exponent * range.max(1e-3).log10()
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
    /// Votes of beams that passed the plane where it has no known surface:
    /// open space (row-major).
    pub open: Vec<u32>,
    /// The transparent votes that were echoes from the surface itself
    /// (row-major); glass and mirrors return them, openings do not.
    pub echo: Vec<u32>,
    /// Beams that passed the plane within a few degrees of its normal with
    /// no echo from it (row-major): glass returns a strong echo there, so
    /// these passed an opening.
    pub bare: Vec<u32>,
    /// A transparent cell with at least this many bare passes over it and
    /// its 8 neighbours, and no surface echo there, is an opening
    /// ([`Surface::Open`]; 0: off).
    pub min_bare_passes: u32,
    /// A transparent region whose echo votes are fewer than this share of
    /// its transparent votes is an opening ([`Surface::Open`]).
    pub min_echo_fraction: f64,
    /// A transparent cell farther than this from every cell with a surface
    /// echo is open space, m (0: no bound): beams pass the infinite plane
    /// far from the surface that echoed, e.g. a small mirror's plane
    /// continued across a hall.
    pub echo_reach: f64,
    /// A transparent cell at the edge of its region is an opening when its
    /// own surface echoes are fewer than this share of what its
    /// neighbours' echo rate predicts for its passes (0: off): glass echoes
    /// at a rate that changes smoothly over the pane with the angles it is
    /// seen at, so a cell above a railing's top edge, passed by the same
    /// beams as the glass below it but never echoing, is open.
    pub echo_deficit_ratio: f64,
    /// ... when the neighbours' rate predicts at least this many echoes
    /// (fewer say nothing).
    pub echo_deficit_min_expected: f64,
    /// The neighbours whose echo rate a cell is held to: the cells with
    /// surface echoes within this distance, m.
    pub echo_deficit_reach: f64,
    /// Votes needed (over a cell and its 8 neighbours) to decide.
    pub min_votes: u32,
    /// A cell without votes of its own is decided by its neighbours only
    /// when voted cells lie on two opposite sides of it (a hole inside a
    /// region), never from one side (the region's edge): otherwise every
    /// region grows by a cell beyond its last vote.
    pub fill_between_votes_only: bool,
    /// Single echoes on the plane brighter than this are from an opaque
    /// surface (set from the plane's own glass echoes; `None`: unknown).
    pub opaque_intensity: Option<f32>,
    /// The median intensity of the plane's glass echoes (surface echoes with
    /// a return behind the plane), when it has any.
    pub glass_echo_intensity: Option<f32>,
    /// Echoes within this cosine of normal incidence are exempt from the
    /// intensity test (glass peaks there like a wall).
    pub peak_cos: f64,
    /// Per incidence bin ([`incidence_bin`]), the strongest strength
    /// (`log10(I · r^k)`, a high quantile) of the plane's glass echoes met
    /// there, where they are many and clearly weaker than the returns
    /// behind them: a single echo stronger than that is from an opaque
    /// surface, a weaker one may be the glass. `None`: no such reference
    /// at that incidence.
    pub glass_strength_at: [Option<f32>; INCIDENCE_BINS],
    /// The range exponent `k` of those strengths.
    pub range_exponent: f64,
    /// Cell states computed by [`EvidenceGrid::finalize`] (empty before).
    states: Vec<Surface>,
    /// Per cell, whether glass could be there unseen
    /// ([`EvidenceGrid::could_hide_glass`]), computed by `finalize`.
    may_hide_glass: Vec<bool>,
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
            echo: vec![0; cols * rows],
            open: vec![0; cols * rows],
            bare: vec![0; cols * rows],
            min_bare_passes: 0,
            min_echo_fraction: 0.0,
            echo_reach: 0.0,
            echo_deficit_ratio: 0.0,
            echo_deficit_min_expected: 30.0,
            echo_deficit_reach: 0.6,
            min_votes,
            fill_between_votes_only: false,
            opaque_intensity: None,
            glass_echo_intensity: None,
            peak_cos: 1.0,
            glass_strength_at: [None; INCIDENCE_BINS],
            range_exponent: 0.0,
            states: Vec::new(),
            may_hide_glass: Vec::new(),
        })
    }

    /// Flat index of the cell holding `uv`, if inside the grid.
    #[inline]
    pub fn index(&self, uv: &Point2<f64>) -> Option<usize> {
        let x = (uv.x - self.min.x) / self.cell;
        let y = (uv.y - self.min.y) / self.cell;
        // Non-negative (NaN fails), so truncation is the floor (no libm
        // call in the per-point loops); `as` saturates huge values.
        if !(x >= 0.0 && y >= 0.0) {
            return None;
        }
        let (i, j) = (x as usize, y as usize);
        (i < self.cols && j < self.rows).then(|| j * self.cols + i)
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
            echo: vec![0; self.echo.len()],
            open: vec![0; self.open.len()],
            bare: vec![0; self.bare.len()],
            states: Vec::new(),
            may_hide_glass: Vec::new(),
            ..self.clone()
        }
    }

    /// Compute every cell's state once, so [`state`](Self::state) is a
    /// lookup: the vote majority per cell, then every connected transparent
    /// region with too few surface echoes is marked [`Surface::Open`]. Votes
    /// added afterwards call for another `finalize`.
    pub fn finalize(&mut self) {
        let n = self.cols * self.rows;
        self.states = (0..n).map(|k| self.vote_state(k)).collect();
        let bare = self.window_sums(&self.bare, 1);
        self.may_hide_glass = self
            .states
            .iter()
            .zip(&bare)
            .map(|(s, b)| *s != Surface::Opaque && *b == 0)
            .collect();
        if self.echo_deficit_ratio > 0.0 {
            self.open_echo_deficits();
        }
        if self.echo_reach > 0.0 {
            let reach = (self.echo_reach / self.cell).round() as usize;
            let near = self.window_sums(&self.echo, reach);
            for (state, near) in self.states.iter_mut().zip(near) {
                if *state == Surface::Transparent && near == 0 {
                    *state = Surface::Open;
                }
            }
        }
        if self.min_bare_passes > 0 {
            let bare = self.window_sums(&self.bare, 1);
            let echo = self.window_sums(&self.echo, 1);
            for (k, state) in self.states.iter_mut().enumerate() {
                if *state == Surface::Transparent
                    && echo[k] == 0
                    && bare[k] >= self.min_bare_passes as u64
                {
                    *state = Surface::Open;
                }
            }
        }
        for region in self.regions(Surface::Transparent) {
            let t: u64 = region.iter().map(|&k| self.transparent[k] as u64).sum();
            let e: u64 = region.iter().map(|&k| self.echo[k] as u64).sum();
            if (e as f64) < self.min_echo_fraction * t as f64 {
                for k in region {
                    self.states[k] = Surface::Open;
                }
            }
        }
    }

    /// Open the transparent cells at the edge of their region whose surface
    /// echoes fall short of their neighbours' echo rate
    /// ([`echo_deficit_ratio`](Self::echo_deficit_ratio); the neighbours
    /// are the cells with echoes within
    /// [`echo_deficit_reach`](Self::echo_deficit_reach)), and the cells
    /// behind them that fall short too, inwards until none does: an extent
    /// overreaches from the glass outwards by up to `echo_reach`, a cell at
    /// a time. A cell inside a pane that echoes less (a sticker, a frame's
    /// shadow) is reached only through such cells, so it stays glass.
    /// Whether an opened cell could hide glass unseen is left as it was: a
    /// tall pane's top, seen steeply, echoes less than its middle too.
    fn open_echo_deficits(&mut self) {
        // The rate of the glass around: passes and echoes of the cells that
        // echoed, within the reach (cells that never echoed, beside the
        // glass, must not dilute the rate they are held to).
        let reach = (self.echo_deficit_reach / self.cell).round().max(1.0) as usize;
        let echoing: Vec<u32> = self
            .transparent
            .iter()
            .zip(&self.echo)
            .map(|(&t, &e)| if e > 0 { t } else { 0 })
            .collect();
        let passes = self.window_sums(&echoing, reach);
        let echoes = self.window_sums(&self.echo, reach);
        let short = |k: usize| {
            let (t, e) = (self.transparent[k] as f64, self.echo[k] as f64);
            // The others alone: the cell's own deficit must not lower the
            // rate it is held to.
            let (around_t, around_e) = (passes[k] as f64 - echoing[k] as f64, echoes[k] as f64 - e);
            let expected = if around_t > 0.0 {
                t * around_e / around_t
            } else {
                0.0
            };
            expected >= self.echo_deficit_min_expected && e < self.echo_deficit_ratio * expected
        };
        // Edge cells first (at the grid's border, or beside a cell that is
        // not transparent); every cell opened makes its transparent
        // neighbours edge cells. The result is the closure (which cells
        // open does not depend on the order).
        let mut queue: Vec<usize> = (0..self.states.len())
            .filter(|&k| {
                self.states[k] == Surface::Transparent
                    && (self.window(k).count() < 9
                        || self
                            .window(k)
                            .any(|m| self.states[m] != Surface::Transparent))
            })
            .collect();
        while let Some(k) = queue.pop() {
            if self.states[k] != Surface::Transparent || !short(k) {
                continue;
            }
            self.states[k] = Surface::Open;
            queue.extend(
                self.window(k)
                    .filter(|&m| self.states[m] == Surface::Transparent),
            );
        }
    }

    /// Per cell, the sum of `counts` over the square window of `reach`
    /// cells in every direction around it (clipped at the grid's edges),
    /// from a summed-area table.
    fn window_sums(&self, counts: &[u32], reach: usize) -> Vec<u64> {
        let (cols, rows) = (self.cols, self.rows);
        let mut sum = vec![0u64; (cols + 1) * (rows + 1)];
        for j in 0..rows {
            for i in 0..cols {
                sum[(j + 1) * (cols + 1) + i + 1] = counts[j * cols + i] as u64
                    + sum[j * (cols + 1) + i + 1]
                    + sum[(j + 1) * (cols + 1) + i]
                    - sum[j * (cols + 1) + i];
            }
        }
        let mut out = Vec::with_capacity(cols * rows);
        for j in 0..rows {
            let (y0, y1) = (j.saturating_sub(reach), (j + reach + 1).min(rows));
            for i in 0..cols {
                let (x0, x1) = (i.saturating_sub(reach), (i + reach + 1).min(cols));
                out.push(
                    sum[y1 * (cols + 1) + x1] + sum[y0 * (cols + 1) + x0]
                        - sum[y0 * (cols + 1) + x1]
                        - sum[y1 * (cols + 1) + x0],
                );
            }
        }
        out
    }

    /// The cells of the 3 x 3 window centred on cell `k` that lie in the
    /// grid, `k` included (fewer than 9 at the grid's border).
    fn window(&self, k: usize) -> impl Iterator<Item = usize> + '_ {
        let (i, j) = ((k % self.cols) as isize, (k / self.cols) as isize);
        (-1..=1)
            .flat_map(move |dj| (-1..=1).map(move |di| (i + di, j + dj)))
            .filter(|&(x, y)| {
                x >= 0 && y >= 0 && (x as usize) < self.cols && (y as usize) < self.rows
            })
            .map(|(x, y)| y as usize * self.cols + x as usize)
    }

    /// The 8-connected regions of cells in `state`, each sorted, ordered by
    /// their first cell.
    pub fn regions(&self, state: Surface) -> Vec<Vec<usize>> {
        let n = self.cols * self.rows;
        let mut seen = vec![false; n];
        let mut out = Vec::new();
        for start in 0..n {
            if seen[start] || self.cell_state(start) != state {
                continue;
            }
            seen[start] = true;
            let mut stack = vec![start];
            let mut cells = Vec::new();
            while let Some(k) = stack.pop() {
                cells.push(k);
                for m in self.window(k) {
                    if !seen[m] && self.cell_state(m) == state {
                        seen[m] = true;
                        stack.push(m);
                    }
                }
            }
            cells.sort_unstable();
            out.push(cells);
        }
        out
    }

    /// Add an open-space vote (a beam passed the plane where it has no
    /// known surface) to the cell holding `uv`.
    pub fn vote_open(&mut self, uv: &Point2<f64>) {
        if let Some(k) = self.index(uv) {
            self.open[k] += 1;
        }
    }

    /// Count a bare pass (a beam through the plane near its normal with no
    /// echo from it) in the cell holding `uv`.
    pub fn vote_bare(&mut self, uv: &Point2<f64>) {
        if let Some(k) = self.index(uv) {
            self.bare[k] += 1;
        }
    }

    /// Add a surface-echo vote (a transparent vote that is also an echo from
    /// the surface itself) to the cell holding `uv`.
    pub fn vote_echo(&mut self, uv: &Point2<f64>) {
        if let Some(k) = self.index(uv) {
            self.transparent[k] += 1;
            self.echo[k] += 1;
        }
    }

    /// Whether a single echo with this intensity, met at this cosine of
    /// incidence and `range` metres, is too bright for the plane's glass: an
    /// opaque surface. Outside the near-normal peak: stronger than the
    /// plane's glass echoes at the same incidence where they tell
    /// ([`glass_strength_at`](Self::glass_strength_at)), else brighter than
    /// [`opaque_intensity`](Self::opaque_intensity).
    pub fn is_opaque_echo(&self, intensity: f32, range: f64, cos_incidence: f64) -> bool {
        if cos_incidence.abs() >= self.peak_cos {
            return false;
        }
        match self.stronger_than_glass(intensity, range, cos_incidence) {
            Some(stronger) => stronger,
            None => self.opaque_intensity.is_some_and(|th| intensity > th),
        }
    }

    /// Whether an echo of this intensity at `range` metres, met at this
    /// cosine of incidence, is stronger than the plane's glass echoes met
    /// at the same incidence; `None` where they give no reference.
    pub fn stronger_than_glass(
        &self,
        intensity: f32,
        range: f64,
        cos_incidence: f64,
    ) -> Option<bool> {
        let reference = self.glass_strength_at[incidence_bin(cos_incidence) as usize]?;
        Some(strength_on_plane(intensity, range, self.range_exponent) > reference as f64)
    }

    /// Surface echoes (glass echoes) counted in the cells within `reach`
    /// metres (a square of cells) of `uv`; 0 outside the grid.
    pub fn echoes_near(&self, uv: &Point2<f64>, reach: f64) -> u32 {
        let x = (uv.x - self.min.x) / self.cell;
        let y = (uv.y - self.min.y) / self.cell;
        let r = (reach / self.cell).round() as i64;
        if !(x.is_finite() && y.is_finite()) {
            return 0;
        }
        let (ci, cj) = (x.floor() as i64, y.floor() as i64);
        let mut total = 0;
        for j in (cj - r).max(0)..=(cj + r).min(self.rows as i64 - 1) {
            for i in (ci - r).max(0)..=(ci + r).min(self.cols as i64 - 1) {
                total += self.echo[j as usize * self.cols + i as usize];
            }
        }
        total
    }

    /// Whether any cell is decided (transparent or opaque).
    pub fn is_decided(&self) -> bool {
        (0..self.cols * self.rows).any(|k| self.cell_state(k) != Surface::Unknown)
    }

    /// Add votes to the cell holding `uv` (ignored outside the grid).
    pub fn vote(&mut self, uv: &Point2<f64>, transparent: u32, opaque: u32) {
        if let Some(k) = self.index(uv) {
            self.transparent[k] += transparent;
            self.opaque[k] += opaque;
        }
    }

    /// Add `n` surface-echo votes to cell `k` (an [`index`](Self::index)).
    pub fn vote_echo_at(&mut self, k: usize, n: u32) {
        self.transparent[k] += n;
        self.echo[k] += n;
    }

    /// Add votes to cell `k` (an [`index`](Self::index)).
    pub fn vote_at(&mut self, k: usize, transparent: u32, opaque: u32) {
        self.transparent[k] += transparent;
        self.opaque[k] += opaque;
    }

    /// Add another grid's votes (same geometry).
    pub fn add(&mut self, other: &EvidenceGrid) {
        for (a, b) in self.transparent.iter_mut().zip(&other.transparent) {
            *a += b;
        }
        for (a, b) in self.opaque.iter_mut().zip(&other.opaque) {
            *a += b;
        }
        for (a, b) in self.echo.iter_mut().zip(&other.echo) {
            *a += b;
        }
        for (a, b) in self.open.iter_mut().zip(&other.open) {
            *a += b;
        }
        for (a, b) in self.bare.iter_mut().zip(&other.bare) {
            *a += b;
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// Whether the grid has no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Decide cell `index` as an opening, whatever its votes (after
    /// [`finalize`](Self::finalize); out-of-range indices are ignored).
    pub fn set_open(&mut self, index: usize) {
        if let Some(s) = self.states.get_mut(index) {
            *s = Surface::Open;
        }
        if let Some(m) = self.may_hide_glass.get_mut(index) {
            *m = false;
        }
    }

    /// Whether glass could be at `uv` without the evidence showing it:
    /// the votes there are not mostly opaque, no beam passed the cell or
    /// its neighbours near normal incidence without an echo (glass would
    /// have answered), and the sensor did not pass through it. True
    /// outside the grid, where nothing is known. Passes far from the
    /// landmark's echoes make a cell [`Surface::Open`] but not this: away
    /// from normal incidence glass stays silent.
    pub fn could_hide_glass(&self, uv: &Point2<f64>) -> bool {
        let Some(k) = self.index(uv) else {
            return true;
        };
        if let Some(m) = self.may_hide_glass.get(k) {
            return *m;
        }
        let bare: u32 = self.window(k).map(|m| self.bare[m]).sum();
        self.vote_state(k) != Surface::Opaque && bare == 0
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
        if self.fill_between_votes_only && self.votes_at(i, j) == 0 && !self.between_votes(i, j) {
            return Surface::Unknown;
        }
        let (mut t, mut o, mut e) = (0u32, 0u32, 0u32);
        for k in self.window(index) {
            t += self.transparent[k];
            o += self.opaque[k];
            e += self.open[k];
        }
        if t + o + e < self.min_votes {
            Surface::Unknown
        } else if t >= o && t >= e {
            Surface::Transparent
        } else if o >= e {
            Surface::Opaque
        } else {
            Surface::Open
        }
    }

    /// All votes of cell (`i`, `j`); 0 outside the grid.
    fn votes_at(&self, i: isize, j: isize) -> u32 {
        if i < 0 || j < 0 || i as usize >= self.cols || j as usize >= self.rows {
            return 0;
        }
        let k = j as usize * self.cols + i as usize;
        self.transparent[k] + self.opaque[k] + self.open[k]
    }

    /// Whether cell (`i`, `j`) has voted neighbours on two opposite sides
    /// (left and right, below and above, or along either diagonal).
    fn between_votes(&self, i: isize, j: isize) -> bool {
        [(1, 0), (0, 1), (1, 1), (1, -1)]
            .iter()
            .any(|&(di, dj)| self.votes_at(i + di, j + dj) > 0 && self.votes_at(i - di, j - dj) > 0)
    }

    /// The state at chart coordinates `uv` (Unknown outside the grid).
    pub fn state(&self, uv: &Point2<f64>) -> Surface {
        self.index(uv)
            .map_or(Surface::Unknown, |k| self.cell_state(k))
    }
}

#[cfg(test)]
mod tests;
