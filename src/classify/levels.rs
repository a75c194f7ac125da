//! The level surfaces of a building: the heights (world z) where floors
//! and ceilings were seen directly. A floor or a ceiling runs on behind a
//! glass partition, so an echo behind a pane at such a height most likely
//! comes from a surface that is there.

use std::sync::OnceLock;

use crate::geometry::fastmath::floor_i64;
use crate::geometry::voxel::FxHashMap;

/// Height bins of the histogram, m.
const BIN: f64 = 0.025;

/// A level holds at least this share of all direct surface echoes within
/// one bin of its height: a floor or ceiling takes a fifth of a scan or
/// more, a wall's echoes spread over its whole height (about 2 % per 7.5 cm
/// of a 3 m wall).
const LEVEL_SHARE: f64 = 0.05;

/// Two levels are at least this far apart, m: a floor's slab is one level.
const SEPARATION: f64 = 0.3;

/// Heights of the surface echoes seen directly, and the levels among them.
#[derive(Debug, Default)]
pub struct Levels {
    bins: FxHashMap<i64, u32>,
    total: u64,
    found: OnceLock<Vec<f64>>,
}

impl Levels {
    /// Count one surface echo seen directly at world height `z`.
    #[inline]
    pub fn add(&mut self, z: f64) {
        if z.is_finite() {
            *self.bins.entry(floor_i64(z / BIN)).or_insert(0) += 1;
            self.total += 1;
            self.found.take();
        }
    }

    /// The heights of the level surfaces, m, ascending: each a local
    /// maximum of the echoes within one bin, holding at least 5 % of them,
    /// the strongest kept where two lie closer than 0.3 m.
    pub fn heights(&self) -> &[f64] {
        self.found.get_or_init(|| self.find())
    }

    /// The index (in [`Levels::heights`]) of the level within `tolerance`
    /// of world height `z`, if any.
    pub fn index_near(&self, z: f64, tolerance: f64) -> Option<usize> {
        index_near(self.heights(), z, tolerance)
    }

    fn find(&self) -> Vec<f64> {
        if self.total == 0 {
            return Vec::new();
        }
        let count = |b: i64| self.bins.get(&b).copied().unwrap_or(0) as f64;
        let window = |b: i64| count(b - 1) + count(b) + count(b + 1);
        let min = LEVEL_SHARE * self.total as f64;
        let mut keys: Vec<i64> = self.bins.keys().copied().collect();
        keys.sort_unstable();
        // Candidates by strength, strongest first; ties by height.
        let mut candidates: Vec<(f64, i64)> = keys
            .iter()
            .map(|&b| (window(b), b))
            .filter(|&(w, b)| w >= min && w >= window(b - 1) && w >= window(b + 1))
            .collect();
        candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut levels: Vec<f64> = Vec::new();
        for (_, b) in candidates {
            let z = (b as f64 + 0.5) * BIN;
            if levels.iter().all(|l| (l - z).abs() >= SEPARATION) {
                levels.push(z);
            }
        }
        levels.sort_by(f64::total_cmp);
        levels
    }
}

/// The index of the first of `heights` within `tolerance` of `z`, if any.
pub fn index_near(heights: &[f64], z: f64, tolerance: f64) -> Option<usize> {
    heights.iter().position(|h| (z - h).abs() <= tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A room: a floor at 0 and a ceiling at 3 m seen densely, walls spread
    /// evenly between. The floor and ceiling are levels, nothing else is.
    #[test]
    fn floor_and_ceiling_are_levels_walls_are_not() {
        let mut levels = Levels::default();
        for i in 0..3000 {
            levels.add(0.004 * (i % 5) as f64);
            levels.add(3.0 - 0.004 * (i % 5) as f64);
        }
        for i in 0..6000 {
            levels.add(3.0 * i as f64 / 6000.0);
        }
        let h = levels.heights().to_vec();
        assert_eq!(h.len(), 2, "{h:?}");
        assert!(h[0].abs() < 0.05 && (h[1] - 3.0).abs() < 0.05, "{h:?}");
        assert_eq!(levels.index_near(0.08, 0.1), Some(0));
        assert_eq!(levels.index_near(1.5, 0.1), None);
    }

    #[test]
    fn no_echoes_no_levels() {
        assert!(Levels::default().heights().is_empty());
    }
}
