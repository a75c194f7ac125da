//! Which variables enter the linear system and where: free variables get
//! contiguous column ranges (poses by id, then planes by id); fixed ones are
//! left out entirely (the gauge fix).

use std::collections::{BTreeMap, BTreeSet};

use super::graph::FactorGraph;
use super::variables::Key;

/// Marker for a key that is held fixed (not in the system).
pub const FIXED: u32 = u32::MAX;

/// Column layout of the free variables.
#[derive(Debug, Clone)]
pub struct Ordering {
    /// Free keys in column order.
    pub keys: Vec<Key>,
    /// First column of each free key (same order as `keys`).
    pub offsets: Vec<usize>,
    /// Total number of columns.
    pub dim: usize,
    index: BTreeMap<Key, u32>,
}

impl Ordering {
    /// The ordering of `graph`'s variables minus `fixed`.
    pub fn new(graph: &FactorGraph, fixed: &BTreeSet<Key>) -> Self {
        let mut keys = Vec::new();
        let mut offsets = Vec::new();
        let mut index = BTreeMap::new();
        let mut dim = 0;
        for key in graph.values.keys().filter(|k| !fixed.contains(k)) {
            index.insert(key, keys.len() as u32);
            keys.push(key);
            offsets.push(dim);
            dim += key.dim();
        }
        Self {
            keys,
            offsets,
            dim,
            index,
        }
    }

    /// Variable index of `key`, or [`FIXED`].
    pub fn var(&self, key: Key) -> u32 {
        self.index.get(&key).copied().unwrap_or(FIXED)
    }
}
