//! Occupied and free space of a whole sequence, as seen directly.
//!
//! A point behind a reflective plane is either real where it was measured
//! (seen through glass) or the mirror image of a real point in front of the
//! plane. Space that beams from other poses saw *directly* (without crossing
//! any reflective pane) tells the two apart without the current frame: a
//! position inside space that other beams passed through cannot hold a
//! surface, and a path that runs through a surface seen from elsewhere cannot
//! have been travelled.
//!
//! Only unambiguous beams write the map (the DUFOMap pitfall: rays to
//! virtual points carve real walls away): a beam that crosses no pane marks
//! its endpoint occupied and the voxels before it free; a beam that crosses a
//! pane carves only the stretch in front of the pane, which is physical under
//! every hypothesis. Within the map "occupied wins": a voxel is free only if
//! no hit was ever recorded in it or next to it (beam footprints, grazing
//! incidence, pose noise).
//!
//! Storage is bricks of 8 × 8 × 8 voxels with two saturating counters each
//! (hits, passes), found through one hash lookup per brick, with the last
//! brick cached: memory grows with the mapped space, not with the number of
//! frames, so it also serves a streamed sequence.

use nalgebra::{Isometry3, Point3, Vector3};

use super::levels::Levels;
use crate::geometry::fastmath::floor_i64;
use crate::geometry::voxel::FxHashMap;

mod sensor_frame;

pub use sensor_frame::{SensorFrameSpace, HORIZONTAL_TOLERANCE};

/// Voxels per brick edge (8, as a shift).
const SHIFT: i64 = 3;
const EDGE: i64 = 1 << SHIFT;
const MASK: i64 = EDGE - 1;
const VOXELS: usize = (EDGE * EDGE * EDGE) as usize;

#[derive(Clone)]
struct Brick {
    hits: [u8; VOXELS],
    passes: [u8; VOXELS],
    /// Voxels with at least one hit: queries skip bricks of pure air.
    hit_voxels: u16,
    /// Voxels with enough hits to block a path.
    solid_voxels: u16,
}

impl Brick {
    fn new() -> Box<Self> {
        Box::new(Self {
            hits: [0; VOXELS],
            passes: [0; VOXELS],
            hit_voxels: 0,
            solid_voxels: 0,
        })
    }
}

/// The occupancy of one voxel as far as direct observation tells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Occupancy {
    /// Never observed directly (or too few beams passed it).
    Unknown,
    /// Beams passed through it and no surface was ever seen in or next to it.
    Free,
    /// A surface was seen in it.
    Occupied,
}

/// Occupied and free space of a sequence (world frame).
pub struct SpaceMap {
    voxel: f64,
    inv: f64,
    min_passes: u8,
    block_hits: u8,
    index: FxHashMap<u64, u32>,
    // Boxed: a brick is about 1 kB, so growing the vector moves pointers,
    // not bricks.
    #[allow(clippy::vec_box)]
    bricks: Vec<Box<Brick>>,
    /// The heights of the surfaces hit, for the floors and ceilings.
    levels: Levels,
    /// The space seen through glass, when any beam was ([`SpaceMap::through`]).
    through: Option<Box<SpaceMap>>,
}

impl std::fmt::Debug for SpaceMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpaceMap")
            .field("voxel", &self.voxel)
            .field("bricks", &self.bricks.len())
            .finish()
    }
}

/// A brick's integer coordinates packed into one key (21 bits per axis, two's
/// complement; exact within ±2^20 bricks).
#[inline]
fn brick_key(b: [i64; 3]) -> u64 {
    let m = (1u64 << 21) - 1;
    (b[0] as u64 & m) | ((b[1] as u64 & m) << 21) | ((b[2] as u64 & m) << 42)
}

#[inline]
fn split(v: [i64; 3]) -> (u64, usize) {
    let key = brick_key([v[0] >> SHIFT, v[1] >> SHIFT, v[2] >> SHIFT]);
    let local = (v[0] & MASK) | ((v[1] & MASK) << SHIFT) | ((v[2] & MASK) << (2 * SHIFT));
    (key, local as usize)
}

impl SpaceMap {
    /// An empty map of `voxel`-sized cubes; a voxel is free once at least
    /// `min_passes` beams passed it, and blocks a path once `block_hits`
    /// returns came from it (stray returns, mixed pixels at depth edges and
    /// people passing by do not wall space off).
    pub fn new(voxel: f64, min_passes: u8, block_hits: u8) -> Self {
        let voxel = voxel.max(1e-3);
        Self {
            voxel,
            inv: 1.0 / voxel,
            min_passes: min_passes.max(1),
            block_hits: block_hits.max(1),
            index: FxHashMap::default(),
            bricks: Vec::new(),
            levels: Levels::default(),
            through: None,
        }
    }

    /// Voxel edge, m.
    pub fn voxel(&self) -> f64 {
        self.voxel
    }

    /// Bricks allocated (each 8³ voxels, 1 KiB).
    pub fn bricks(&self) -> usize {
        self.bricks.len()
    }

    #[inline]
    fn voxel_of(&self, p: &Point3<f64>) -> [i64; 3] {
        [
            floor_i64(p.x * self.inv),
            floor_i64(p.y * self.inv),
            floor_i64(p.z * self.inv),
        ]
    }

    /// The number of the brick with `key`, allocated on first use.
    fn brick_index(&mut self, key: u64) -> u32 {
        let next = self.bricks.len() as u32;
        let b = *self.index.entry(key).or_insert(next);
        if b == next {
            self.bricks.push(Brick::new());
        }
        b
    }

    #[inline]
    fn counts(&self, v: [i64; 3]) -> (u8, u8) {
        let (key, local) = split(v);
        match self.index.get(&key) {
            Some(&b) => {
                let brick = &self.bricks[b as usize];
                (brick.hits[local], brick.passes[local])
            }
            None => (0, 0),
        }
    }

    /// Record one directly seen beam: from `origin` towards `end`, the voxels
    /// up to `stop_short` metres before `end` were passed; `end` itself is a
    /// surface when `hit`.
    pub fn add_beam(
        &mut self,
        origin: &Point3<f64>,
        end: &Point3<f64>,
        stop_short: f64,
        hit: bool,
    ) {
        let delta = end - origin;
        let len = delta.norm();
        if !(len.is_finite()) {
            return;
        }
        if len - stop_short > 0.0 {
            let (mut cache_key, mut cache) = (u64::MAX, 0u32);
            walk(self.voxel, origin, &(delta / len), len - stop_short, |v| {
                let (key, local) = split(v);
                if key != cache_key {
                    cache = self.brick_index(key);
                    cache_key = key;
                }
                let c = &mut self.bricks[cache as usize].passes[local];
                *c = c.saturating_add(1);
                false
            });
        }
        if hit {
            self.levels.add(end.z);
            let (key, local) = split(self.voxel_of(end));
            let block_hits = self.block_hits;
            let b = self.brick_index(key) as usize;
            let brick = &mut self.bricks[b];
            if brick.hits[local] == 0 {
                brick.hit_voxels += 1;
            }
            if brick.hits[local] == block_hits - 1 {
                brick.solid_voxels += 1;
            }
            brick.hits[local] = brick.hits[local].saturating_add(1);
        }
    }

    /// An empty map with this one's voxel and thresholds: for the space
    /// seen through glass ([`set_through`](Self::set_through)).
    pub fn empty_like(&self) -> Self {
        Self::new(self.voxel, self.min_passes, self.block_hits)
    }

    /// Keep `through`, the space seen through glass (the beams of confirmed
    /// transmissions behind their panes, from the pane to their echo), apart
    /// from the space seen directly: its evidence is only as good as the
    /// confirmation.
    pub fn set_through(&mut self, through: SpaceMap) {
        self.through = Some(Box::new(through));
    }

    /// The space seen through glass, when kept
    /// ([`set_through`](Self::set_through)).
    pub fn through(&self) -> Option<&SpaceMap> {
        self.through.as_deref()
    }

    /// What direct observation says about the voxel holding `p`: occupied
    /// when a surface was seen in it, free when enough beams passed it and no
    /// surface was seen in it or in any of its 26 neighbours.
    pub fn occupancy(&self, p: &Point3<f64>) -> Occupancy {
        self.occupancy_clear_of(p, 0.0)
    }

    /// [`SpaceMap::occupancy`], with free space also kept `clearance`
    /// metres (at least one voxel, at most four) from every seen surface: a
    /// position computed by mirroring at a plane carries the plane's error,
    /// which grows with the distance from it.
    pub fn occupancy_clear_of(&self, p: &Point3<f64>, clearance: f64) -> Occupancy {
        let v = self.voxel_of(p);
        let (hits, passes) = self.counts(v);
        if hits > 0 {
            return Occupancy::Occupied;
        }
        if passes < self.min_passes {
            return Occupancy::Unknown;
        }
        let k = ((clearance * self.inv).ceil() as i64).clamp(1, 4);
        if self.hit_within(v, k) {
            return Occupancy::Unknown;
        }
        Occupancy::Free
    }

    /// Whether a surface was seen in the voxel holding `p` (3DRef labels a
    /// point within 0.15 m of a surface as on it; a neighbour voxel would
    /// reach 0.2-0.35 m).
    pub fn surface_at(&self, p: &Point3<f64>) -> bool {
        self.counts(self.voxel_of(p)).0 > 0
    }

    /// Whether a voxel within `k` voxels of `v` (each axis) holds a seen
    /// surface.
    fn hit_within(&self, v: [i64; 3], k: i64) -> bool {
        let (lo, hi) = (v.map(|c| c - k), v.map(|c| c + k));
        // Brick by brick: at most two per axis, bricks without hits skipped.
        for bz in lo[2] >> SHIFT..=hi[2] >> SHIFT {
            for by in lo[1] >> SHIFT..=hi[1] >> SHIFT {
                for bx in lo[0] >> SHIFT..=hi[0] >> SHIFT {
                    let Some(&b) = self.index.get(&brick_key([bx, by, bz])) else {
                        continue;
                    };
                    let brick = &self.bricks[b as usize];
                    if brick.hit_voxels == 0 {
                        continue;
                    }
                    let base = [bx << SHIFT, by << SHIFT, bz << SHIFT];
                    let from = [0, 1, 2].map(|a| (lo[a] - base[a]).max(0));
                    let to = [0, 1, 2].map(|a| (hi[a] - base[a]).min(MASK));
                    for z in from[2]..=to[2] {
                        for y in from[1]..=to[1] {
                            for x in from[0]..=to[0] {
                                let local = (x | (y << SHIFT) | (z << (2 * SHIFT))) as usize;
                                if brick.hits[local] > 0 {
                                    return true;
                                }
                            }
                        }
                    }
                }
            }
        }
        false
    }

    /// Whether the segment from `a` to `b`, less `margin` metres at each
    /// end, runs through a voxel where a surface was seen (at least
    /// `block_hits` returns): a path no beam could have travelled.
    pub fn blocked(&self, a: &Point3<f64>, b: &Point3<f64>, margin: f64) -> bool {
        let delta = b - a;
        let len = delta.norm();
        if !(len > 2.0 * margin) {
            return false;
        }
        let dir = delta / len;
        let start = a + dir * margin;
        // Brick by brick, and voxel by voxel only inside bricks that hold a
        // hit: most of a long path runs through air or unseen space.
        let brick_edge = self.voxel * EDGE as f64;
        let mut hit = false;
        walk_spans(brick_edge, &start, &dir, len - 2.0 * margin, |b, t0, t1| {
            let Some(&index) = self.index.get(&brick_key(b)) else {
                return false;
            };
            let brick = &self.bricks[index as usize];
            if brick.solid_voxels == 0 {
                return false;
            }
            let entry = start + dir * t0;
            walk_spans(self.voxel, &entry, &dir, t1 - t0, |v, _, _| {
                let inside = [0, 1, 2].iter().all(|&a| v[a] >> SHIFT == b[a]);
                hit = inside && brick.hits[split(v).1] >= self.block_hits;
                hit
            });
            hit
        });
        hit
    }

    /// The floors and ceilings seen directly (world z).
    pub fn levels(&self) -> &Levels {
        &self.levels
    }

    /// A view answering in the sensor frame of a frame with pose `pose`.
    pub fn in_sensor_frame(&self, pose: Isometry3<f64>) -> SensorFrameSpace<'_> {
        SensorFrameSpace {
            map: self,
            rotation: pose.rotation.to_rotation_matrix().into_inner(),
            translation: pose.translation.vector,
        }
    }
}

/// Walk the voxels of edge `voxel` along `origin + t·dir` for `t` in
/// `[0, length]` (Amanatides–Woo), calling `f` on each until it returns
/// `true`.
fn walk(
    voxel: f64,
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    length: f64,
    mut f: impl FnMut([i64; 3]) -> bool,
) {
    walk_spans(voxel, origin, dir, length, |v, _, _| f(v));
}

/// [`walk`], also passing the range of `t` spent in each cell.
fn walk_spans(
    voxel: f64,
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    length: f64,
    mut f: impl FnMut([i64; 3], f64, f64) -> bool,
) {
    let inv = 1.0 / voxel;
    let mut v = [
        floor_i64(origin.x * inv),
        floor_i64(origin.y * inv),
        floor_i64(origin.z * inv),
    ];
    let mut step = [0i64; 3];
    let mut t_next = [f64::INFINITY; 3];
    let mut t_delta = [f64::INFINITY; 3];
    for a in 0..3 {
        let u = dir[a];
        if u > 0.0 {
            step[a] = 1;
            t_delta[a] = voxel / u;
            t_next[a] = ((v[a] + 1) as f64 * voxel - origin[a]) / u;
        } else if u < 0.0 {
            step[a] = -1;
            t_delta[a] = -voxel / u;
            t_next[a] = (v[a] as f64 * voxel - origin[a]) / u;
        }
    }
    // Bounded whatever the direction: a walk of `length` crosses at most
    // this many voxel faces.
    let max_steps = (3.0 * length * inv).ceil() as usize + 3;
    let mut t_in = 0.0;
    for _ in 0..max_steps {
        let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
            0
        } else if t_next[1] <= t_next[2] {
            1
        } else {
            2
        };
        let t_out = t_next[a].min(length);
        if f(v, t_in, t_out) || t_next[a] > length {
            return;
        }
        t_in = t_next[a];
        v[a] += step[a];
        t_next[a] += t_delta[a];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A room seen from two poses: a wall at x = 5 (hits), the air before
    /// it carved. The air is free, the wall occupied, behind the wall
    /// unknown; a segment through the wall is blocked, one in the air not.
    fn room() -> SpaceMap {
        let mut map = SpaceMap::new(0.1, 2, 1);
        for origin in [Point3::new(0.0, 0.0, 1.0), Point3::new(1.0, 0.5, 1.2)] {
            for j in -40..=40 {
                for k in 0..=20 {
                    let end = Point3::new(5.0, j as f64 * 0.05, k as f64 * 0.1);
                    map.add_beam(&origin, &end, 0.2, true);
                }
            }
        }
        map
    }

    #[test]
    fn carved_air_is_free_walls_occupied_and_behind_unknown() {
        let map = room();
        assert_eq!(map.occupancy(&Point3::new(2.5, 0.0, 1.0)), Occupancy::Free);
        assert_eq!(
            map.occupancy(&Point3::new(5.0, 0.3, 1.0)),
            Occupancy::Occupied
        );
        assert_eq!(
            map.occupancy(&Point3::new(6.0, 0.0, 1.0)),
            Occupancy::Unknown
        );
        // Next to the wall nothing is free, even where beams passed.
        assert_ne!(map.occupancy(&Point3::new(4.92, 0.0, 1.0)), Occupancy::Free);
        // Far to the side no beam passed.
        assert_eq!(
            map.occupancy(&Point3::new(2.5, 8.0, 1.0)),
            Occupancy::Unknown
        );
        let a = Point3::new(3.0, 0.0, 1.0);
        assert!(map.blocked(&a, &Point3::new(7.0, 0.0, 1.0), 0.2));
        assert!(!map.blocked(&a, &Point3::new(1.0, 0.2, 1.1), 0.2));
        // The margin keeps a segment ending on the wall unblocked.
        assert!(!map.blocked(&a, &Point3::new(5.0, 0.0, 1.0), 0.2));
        // Memory grows with the space, not with the beams: a second pass
        // over the same beams allocates nothing.
        let mut again = room();
        let bricks = again.bricks();
        again.add_beam(
            &Point3::new(0.0, 0.0, 1.0),
            &Point3::new(5.0, 0.0, 1.0),
            0.2,
            true,
        );
        assert_eq!(again.bricks(), bricks);
    }

    /// A grazing beam (85° incidence on the wall, passing 2 cm from it) does
    /// not make the wall's neighbourhood free.
    #[test]
    fn a_grazing_beam_does_not_free_the_wall() {
        let mut map = room();
        let origin = Point3::new(4.98, -3.0, 1.0);
        for _ in 0..5 {
            map.add_beam(&origin, &Point3::new(4.98, 3.0, 1.0), 0.2, false);
        }
        assert_ne!(map.occupancy(&Point3::new(4.98, 0.0, 1.0)), Occupancy::Free);
    }

    /// The brick-by-brick path test answers as a plain voxel walk does, on
    /// random surfaces and random segments.
    #[test]
    fn brick_skipping_path_test_matches_the_voxel_walk() {
        let mut rng = crate::rng::SplitMix64::new(21);
        let mut map = SpaceMap::new(0.1, 2, 2);
        let origin = Point3::new(0.0, 0.0, 0.0);
        for _ in 0..3000 {
            let end = Point3::new(
                rng.unit() * 8.0 - 4.0,
                rng.unit() * 8.0 - 4.0,
                rng.unit() * 2.0,
            );
            map.add_beam(&origin, &end, 0.2, true);
            if rng.unit() < 0.5 {
                map.add_beam(&origin, &end, 0.2, true);
            }
        }
        let mut blocked = 0;
        for _ in 0..2000 {
            let a = Point3::new(
                rng.unit() * 10.0 - 5.0,
                rng.unit() * 10.0 - 5.0,
                rng.unit() * 2.0,
            );
            let b = Point3::new(
                rng.unit() * 10.0 - 5.0,
                rng.unit() * 10.0 - 5.0,
                rng.unit() * 2.0,
            );
            let fast = map.blocked(&a, &b, 0.05);
            let len = (b - a).norm();
            let mut slow = false;
            if len > 0.1 {
                let dir = (b - a) / len;
                walk(0.1, &(a + dir * 0.05), &dir, len - 0.1, |v| {
                    slow = map.counts(v).0 >= 2;
                    slow
                });
            }
            assert_eq!(fast, slow, "{a} -> {b}");
            blocked += fast as usize;
        }
        assert!(blocked > 100 && blocked < 1900, "{blocked} of 2000 blocked");
    }

    /// The voxel walk visits a face-connected chain from the start voxel to
    /// the end voxel, whatever the direction.
    #[test]
    fn the_walk_is_a_connected_chain_from_start_to_end() {
        let mut rng = crate::rng::SplitMix64::new(9);
        for _ in 0..500 {
            let a = Point3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 4.0 - 2.0, rng.unit());
            let b = Point3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 4.0 - 2.0, rng.unit());
            let len = (b - a).norm();
            if len < 1e-3 {
                continue;
            }
            let mut visited = Vec::new();
            walk(0.1, &a, &((b - a) / len), len, |v| {
                visited.push(v);
                false
            });
            let key = |p: &Point3<f64>| [0, 1, 2].map(|i| (p[i] / 0.1).floor() as i64);
            assert_eq!(visited[0], key(&a));
            let last = *visited.last().unwrap();
            let kb = key(&b);
            // The end voxel, or its face neighbour when b sits on a face.
            let gap: i64 = (0..3).map(|i| (last[i] - kb[i]).abs()).sum();
            assert!(gap <= 1, "{last:?} vs {kb:?}");
            for w in visited.windows(2) {
                let d: i64 = (0..3).map(|i| (w[0][i] - w[1][i]).abs()).sum();
                assert_eq!(d, 1, "not face-connected: {:?}", w);
            }
        }
    }
}
