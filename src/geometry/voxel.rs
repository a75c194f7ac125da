//! Voxel keys, the Fx hash and a fast, deterministic voxel set for thinning
//! point sets.

use super::fastmath::floor_i64;

use std::hash::{BuildHasherDefault, Hasher};

/// The integer voxel of `p` for cubes of edge `size`.
#[inline]
pub fn voxel_key(p: [f64; 3], size: f64) -> [i64; 3] {
    let inv = 1.0 / size;
    [
        floor_i64(p[0] * inv),
        floor_i64(p[1] * inv),
        floor_i64(p[2] * inv),
    ]
}

/// The Fx hash (as used inside rustc): a multiply-rotate hash, much faster
/// than SipHash for small integer keys and deterministic across runs.
#[derive(Debug, Default, Clone, Copy)]
pub struct FxHasher {
    hash: u64,
}

const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl FxHasher {
    #[inline]
    fn add(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(SEED);
    }
}

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.add(u64::from_le_bytes(c.try_into().unwrap_or([0; 8])));
        }
        for &b in chunks.remainder() {
            self.add(b as u64);
        }
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }

    #[inline]
    fn write_i64(&mut self, i: i64) {
        self.add(i as u64);
    }

    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.add(i as u64);
    }

    /// The high bits of the product depend on every input bit, the low
    /// ones only on the low input bits; the table indexes by the low bits,
    /// so they are rotated in (as rustc-hash 2 does). Without it, packed
    /// voxel keys that differ only in y or z all probe the same slot.
    #[inline]
    fn finish(&self) -> u64 {
        self.hash.rotate_left(26)
    }
}

/// A hash map with the Fx hash.
pub type FxHashMap<K, V> = std::collections::HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// Voxels per brick edge of a [`VoxelSet`] (8 × 8 × 8 = 512 bits per brick).
const BRICK: i64 = 8;
/// `u64` words per brick.
const BRICK_WORDS: usize = (BRICK * BRICK * BRICK / 64) as usize;

/// A set of occupied voxels, each optionally tagged (e.g. by class), for
/// thinning a stream of points to the first point per voxel.
///
/// Voxels are bits in 8 × 8 × 8 bricks, as in OpenVDB's leaf nodes: a brick
/// holds a neighbourhood in one cache line, and a small direct-mapped cache
/// of recent bricks answers most inserts of a scan (whose consecutive points
/// alternate between a few neighbouring bricks) without a hash lookup. Brick indices are packed in 20 bits per
/// axis: exact within ±2^22 voxels of the origin (±126 km at 3 cm); farther
/// away distinct voxels may share a bit, which only thins a little more.
#[derive(Debug, Clone)]
pub struct VoxelSet {
    inv_size: f64,
    bricks: FxHashMap<u64, u32>,
    bits: Vec<u64>,
    /// Recently used (brick key, word offset); `u64::MAX` marks an empty
    /// slot, so the one brick with that key is never cached.
    cache: Box<[(u64, u32); CACHE]>,
}

/// Slots of the brick cache of a [`VoxelSet`].
const CACHE: usize = 64;

impl VoxelSet {
    /// An empty set of cubes of edge `size` metres (must be > 0).
    pub fn new(size: f64) -> Self {
        Self {
            inv_size: 1.0 / size,
            bricks: FxHashMap::default(),
            bits: Vec::new(),
            cache: Box::new([(u64::MAX, 0); CACHE]),
        }
    }

    /// Insert the voxel of `p` under `tag` (only its low 4 bits are used:
    /// up to 16 independent layers). Returns whether it was new.
    ///
    /// Always inlined: it is the body of the thinning loops (support, maps),
    /// and whether the compiler inlined it moved with unrelated changes
    /// (3 % of a whole `detect` run on the ten shared frames).
    #[inline(always)]
    pub fn insert(&mut self, p: [f64; 3], tag: u8) -> bool {
        let k = [
            floor_i64(p[0] * self.inv_size),
            floor_i64(p[1] * self.inv_size),
            floor_i64(p[2] * self.inv_size),
        ];
        let m = (1u64 << 20) - 1;
        // `>> 3` on i64 is floor division by the brick edge.
        let key = ((k[0] >> 3) as u64 & m)
            | (((k[1] >> 3) as u64 & m) << 20)
            | (((k[2] >> 3) as u64 & m) << 40)
            | ((tag as u64 & 0xF) << 60);
        let slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 58) as usize % CACHE;
        let base = match self.cache[slot] {
            (cached, base) if cached == key => base as usize,
            _ => {
                let next = self.bricks.len() as u32;
                let id = *self.bricks.entry(key).or_insert(next);
                if id == next {
                    self.bits.extend_from_slice(&[0; BRICK_WORDS]);
                }
                let base = id as usize * BRICK_WORDS;
                if key != u64::MAX {
                    self.cache[slot] = (key, base as u32);
                }
                base
            }
        };
        let bit =
            ((k[0] & (BRICK - 1)) | (k[1] & (BRICK - 1)) << 3 | (k[2] & (BRICK - 1)) << 6) as usize;
        let word = &mut self.bits[base + (bit >> 6)];
        let mask = 1u64 << (bit & 63);
        let new = *word & mask == 0;
        *word |= mask;
        new
    }

    /// Number of occupied voxels (over all tags).
    pub fn len(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Whether no voxel is occupied.
    pub fn is_empty(&self) -> bool {
        self.bits.iter().all(|&w| w == 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashSet;

    proptest! {
        /// The brick set agrees with a plain set of (voxel, tag) keys.
        #[test]
        fn voxel_set_matches_a_hash_set(
            points in proptest::collection::vec(
                ((-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0), 0u8..3),
                1..400,
            ),
            size in 0.05f64..0.5,
        ) {
            let mut set = VoxelSet::new(size);
            let mut reference = HashSet::new();
            for &((x, y, z), tag) in &points {
                let p = [x, y, z];
                prop_assert_eq!(set.insert(p, tag), reference.insert((voxel_key(p, size), tag)));
            }
            prop_assert_eq!(set.len(), reference.len());
        }
    }

    #[test]
    fn voxel_set_separates_neighbours_across_brick_faces() {
        let mut set = VoxelSet::new(1.0);
        // -0.5 and 0.5 are in voxels -1 and 0: different bricks (-1 and 0).
        assert!(set.insert([-0.5, 0.0, 0.0], 0));
        assert!(set.insert([0.5, 0.0, 0.0], 0));
        assert!(set.insert([7.5, 0.0, 0.0], 0));
        assert!(set.insert([8.5, 0.0, 0.0], 0));
        assert!(!set.insert([8.9, 0.2, 0.7], 0));
        assert!(set.insert([8.9, 0.2, 0.7], 1));
        assert_eq!(set.len(), 5);
        assert!(!set.is_empty());
    }
}
