//! Voxel keys and a fast, deterministic voxel set for thinning point sets.

use super::fastmath::floor_i64;

use std::collections::HashSet;
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

/// `voxel_key` packed into one `u64` (21 bits per axis, two's complement),
/// exact for voxel indices within ±2^20 (±52 km at 5 cm voxels); beyond that
/// distinct voxels may share a key, which only thins a little more.
#[inline]
pub fn packed_voxel_key(p: [f64; 3], size: f64) -> u64 {
    let k = voxel_key(p, size);
    let m = (1u64 << 21) - 1;
    ((k[0] as u64) & m) | (((k[1] as u64) & m) << 21) | (((k[2] as u64) & m) << 42)
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

/// A hash set with the Fx hash.
pub type FxHashSet<T> = HashSet<T, BuildHasherDefault<FxHasher>>;
