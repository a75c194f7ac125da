//! Surfaces seen through a landmark: where echoes on the transmitted side
//! of its echo split landed. A transmitted echo needs a surface where it
//! was measured, and 3DRef labels whatever lands on a surface behind glass
//! an Obstacle, its own reflection included (a floor that runs on behind a
//! glass partition is its own mirror image, so the seen space never
//! confirms its transmissions; its echo strengths do).

use nalgebra::Point3;

use super::glass_or_mirror::LandedEcho;
use crate::geometry::fastmath::floor_i64;
use crate::geometry::voxel::FxHashMap;
use crate::reflect::EchoSplit;

/// Strength bins of each voxel's counts: 0.25 decades from -1 to 7
/// (the range of `log10(I r^k / cos)` the echo split's histogram covers).
const LOG_MIN: f32 = -1.0;
const BIN: f32 = 0.25;
const BINS: usize = 32;

/// The strengths of the echoes behind one landmark, counted per voxel
/// (bounded by the volume behind it, whatever the number of frames).
#[derive(Debug, Clone, Default)]
pub struct LandedStrengths {
    voxels: FxHashMap<[i64; 3], [u16; BINS]>,
}

impl LandedStrengths {
    /// Count `echo` in its voxel of edge `voxel`, m.
    pub fn add(&mut self, echo: &LandedEcho, voxel: f64) {
        let key = echo.position.map(|c| floor_i64(f64::from(c) / voxel));
        let bin = (((echo.strength - LOG_MIN) / BIN).max(0.0) as usize).min(BINS - 1);
        let counts = self.voxels.entry(key).or_insert([0; BINS]);
        counts[bin] = counts[bin].saturating_add(1);
    }

    /// The centres of the voxels (edge `voxel`, m) that hold a surface: at
    /// least two of their echoes fell on the transmitted side of `split`
    /// and no more on its reflected side (each beyond its undecided band).
    /// A strong echo or two among many weak ones are reflections of
    /// something bright, or strengths thrown by a bad incidence estimate; a
    /// voxel where most echoes are strong holds a surface. `None` from a
    /// split not fitted to the landmark's own echoes (it cannot tell a
    /// strong reflection off coated glass).
    pub fn surfaces<'a>(
        &'a self,
        split: &'a EchoSplit,
        voxel: f64,
    ) -> Option<impl Iterator<Item = Point3<f64>> + 'a> {
        if split.from_physics {
            return None;
        }
        let centre = |b: usize| f64::from(LOG_MIN + BIN * (b as f32 + 0.5));
        let (lo, hi) = (split.threshold - split.band, split.threshold + split.band);
        let side = move |counts: &[u16; BINS]| {
            let (mut weak, mut strong) = (0u32, 0u32);
            for (b, &n) in counts.iter().enumerate() {
                let c = centre(b);
                if c < lo {
                    weak += u32::from(n);
                } else if c > hi {
                    strong += u32::from(n);
                }
            }
            if split.weak_is_reflection {
                (strong, weak)
            } else {
                (weak, strong)
            }
        };
        Some(
            self.voxels
                .iter()
                .filter(move |(_, counts)| {
                    let (transmitted, reflected) = side(counts);
                    transmitted >= 2 && transmitted >= reflected
                })
                .map(move |(v, _)| {
                    Point3::new(
                        (v[0] as f64 + 0.5) * voxel,
                        (v[1] as f64 + 0.5) * voxel,
                        (v[2] as f64 + 0.5) * voxel,
                    )
                }),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(weak_is_reflection: bool) -> EchoSplit {
        EchoSplit {
            threshold: 2.0,
            band: 0.1,
            range_exponent: 2.0,
            incidence_correction: true,
            weak_is_reflection,
            weak_mean: 1.0,
            strong_mean: 3.0,
            weak_spread: 0.2,
            strong_spread: 0.2,
            from_physics: false,
        }
    }

    fn echo(x: f32, strength: f32) -> LandedEcho {
        LandedEcho {
            position: [x, 0.05, 0.05],
            strength,
        }
    }

    /// A voxel where most echoes are transmitted holds a surface; one where
    /// two strong echoes stand among many weak ones (a bright object
    /// reflected), or one strong echo alone, does not; a split from physics
    /// marks nothing.
    #[test]
    fn a_surface_where_most_echoes_are_transmitted() {
        let mut landed = LandedStrengths::default();
        let voxel = 0.1;
        // Voxel 0: three strong, two weak. Voxel 1: two strong, five weak.
        // Voxel 2: one strong.
        for s in [3.0, 3.1, 2.9, 1.0, 0.9] {
            landed.add(&echo(0.05, s), voxel);
        }
        for s in [3.0, 3.2, 1.0, 1.1, 0.8, 1.0, 1.2] {
            landed.add(&echo(0.15, s), voxel);
        }
        landed.add(&echo(0.25, 3.0), voxel);
        let found: Vec<Point3<f64>> = landed.surfaces(&split(true), voxel).unwrap().collect();
        assert_eq!(found.len(), 1, "{found:?}");
        assert!((found[0] - Point3::new(0.05, 0.05, 0.05)).norm() < 1e-9);
        // Where the strong group is the reflections, the weak echoes are
        // the transmitted ones: voxel 1 (five weak) and voxel 0 (two weak,
        // three strong: more reflected) swap.
        let swapped: Vec<Point3<f64>> = landed.surfaces(&split(false), voxel).unwrap().collect();
        assert_eq!(swapped.len(), 1, "{swapped:?}");
        assert!((swapped[0] - Point3::new(0.15, 0.05, 0.05)).norm() < 1e-9);
        let physics = EchoSplit {
            from_physics: true,
            ..split(true)
        };
        assert!(landed.surfaces(&physics, voxel).is_none());
    }
}
