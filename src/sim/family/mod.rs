//! Scene families: random buildings of one kind, drawn within physical
//! ranges, so that the method is measured on scenes nobody tuned it on.
//!
//! A family turns a seed into a scene: room and corridor sizes, pane widths
//! (0.6-3 m) and mullions (0.05-0.3 m), glass reflectance and
//! transmittance, mirror reflectance, albedos, clutter in front of and
//! behind the glass (furniture, people), the walk or loop of the sensor
//! (0.3-1.5 m/s, its height and mounting tilt), range noise and dropouts.
//! [`generate`] draws it, builds it through the scene-file validation and
//! checks that it is sound ([`validate`]: the path keeps clear of every
//! surface, no two solids overlap); a draw that fails is drawn again from
//! the next sub-seed, so every (family, seed) gives one scene, the same on
//! every machine.
//!
//! **Splits.** Seeds `0..1000` are the development split: parameters are
//! chosen on them only. Seeds from [`HELD_OUT_START`] up are held out:
//! their figures are reported and never tuned to (`docs/benchmark.md`).
//!
//! A family is one type implementing [`SceneFamily`] in its own file and
//! one line in [`FAMILIES`].

mod atrium;
mod coated;
mod corridor;
mod draft;
mod furnish;
mod glass_in_glass;
mod mirror_hall;
mod mixed;
mod office;
mod storefront;

use std::path::Path;

use glam::DVec3;

pub use draft::{there_and_back, Draft, GlassStyle, Glazing, PANEL_OFFSET, PATH_CLEARANCE};

use super::raycast::SceneIndex;
use super::Scene;
use crate::{Error, Result};

/// First seed of the held-out split (seeds below 1000 are development).
pub const HELD_OUT_START: u64 = 1_000_000;
/// Seeds `0..DEVELOPMENT_END` are the development split.
pub const DEVELOPMENT_END: u64 = 1000;
/// The sensor's path keeps at least this far from every surface, metres.
pub const SURFACE_CLEARANCE: f64 = 0.3;
/// Draws tried per (family, seed) before giving up.
const ATTEMPTS: u64 = 32;

/// A kind of building, drawn at random from a seed.
pub trait SceneFamily: Sync {
    /// Name on the command line (`--family NAME`).
    fn name(&self) -> &'static str;
    /// One line on what the family varies.
    fn description(&self) -> &'static str;
    /// Draw one scene into `draft` (layout, path, then clutter); an error
    /// says why this draw cannot be built (it is drawn again).
    fn draw(&self, draft: &mut Draft) -> std::result::Result<(), String>;
}

/// Every family, in listing order.
pub const FAMILIES: &[&dyn SceneFamily] = &[
    &office::Office,
    &corridor::GlassCorridor,
    &atrium::Atrium,
    &mirror_hall::MirrorHall,
    &storefront::Storefront,
    &glass_in_glass::GlassInGlass,
    &coated::CoatedGlass,
    &mixed::Mixed,
];

/// The family called `name`.
pub fn family(name: &str) -> Result<&'static dyn SceneFamily> {
    FAMILIES
        .iter()
        .copied()
        .find(|f| f.name() == name)
        .ok_or_else(|| {
            Error::Config(format!(
                "unknown scene family '{name}' (families: {})",
                names().join(", ")
            ))
        })
}

/// Names of every family.
pub fn names() -> Vec<&'static str> {
    FAMILIES.iter().map(|f| f.name()).collect()
}

/// Which split a seed belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    /// Seeds `0..1000`: parameters are chosen here.
    Development,
    /// Seeds from [`HELD_OUT_START`]: reported, never tuned to.
    HeldOut,
}

impl Split {
    /// The first `n` seeds of the split.
    pub fn seeds(self, n: usize) -> Vec<u64> {
        let start = match self {
            Split::Development => 0,
            Split::HeldOut => HELD_OUT_START,
        };
        (start..start + n as u64).collect()
    }

    /// The split of `seed`, `None` between the two.
    pub fn of(seed: u64) -> Option<Self> {
        if seed < DEVELOPMENT_END {
            Some(Split::Development)
        } else if seed >= HELD_OUT_START {
            Some(Split::HeldOut)
        } else {
            None
        }
    }

    /// Name as printed (`development`, `held-out`).
    pub fn name(self) -> &'static str {
        match self {
            Split::Development => "development",
            Split::HeldOut => "held-out",
        }
    }
}

/// A generated scene and the scene file that rebuilds it.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The validated scene.
    pub scene: Scene,
    /// Its scene file (TOML): `specular simulate --scene FILE` makes the
    /// same frames.
    pub toml: String,
}

/// The scene of `family` for `seed`.
pub fn generate(family_name: &str, seed: u64) -> Result<Generated> {
    let family = family(family_name)?;
    let origin = format!("family:{family_name}/{seed}");
    let mut why = String::new();
    for attempt in 0..ATTEMPTS {
        let mut draft = Draft::new(
            &format!("{family_name}-{seed}"),
            draw_seed(family_name, seed, attempt),
        );
        if let Err(e) = family.draw(&mut draft) {
            why = e;
            continue;
        }
        draft.file.description = format!("{} (seed {seed})", family.description());
        let toml =
            toml::to_string(&draft.file).map_err(|e| Error::Config(format!("{origin}: {e}")))?;
        let scene = Scene::from_file(draft.file, Path::new(&origin))?;
        match validate(&scene) {
            Ok(()) => return Ok(Generated { scene, toml }),
            Err(e) => why = e,
        }
    }
    Err(Error::Config(format!(
        "{origin}: no sound scene in {ATTEMPTS} draws (last: {why})"
    )))
}

/// The generator seed of one draw: a hash of family, seed and attempt.
fn draw_seed(family: &str, seed: u64, attempt: u64) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in family.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    let mut g = crate::rng::SplitMix64::new(h ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let base = g.next_u64();
    crate::rng::SplitMix64::new(base ^ attempt).next_u64()
}

/// A scene is sound when its path keeps [`SURFACE_CLEARANCE`] from every
/// surface (sampled every 5 cm over one pass). That no two solids overlap
/// is kept as they are placed ([`Draft::solid`]).
pub fn validate(scene: &Scene) -> std::result::Result<(), String> {
    let index = SceneIndex::new(&scene.surfaces);
    let t = &scene.trajectory;
    let n = ((t.length() / 0.05).ceil() as usize).max(2);
    for i in 0..=n {
        let s = t.length() * i as f64 / n as f64;
        let p = t.position(s);
        if let Some(d) = index.distance_within(p, SURFACE_CLEARANCE) {
            return Err(format!(
                "the path passes {d:.2} m from a surface at ({:.2}, {:.2}, {:.2})",
                p.x, p.y, p.z
            ));
        }
    }
    Ok(())
}

/// Whether two axis-aligned boxes' interiors overlap.
pub fn boxes_overlap(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> bool {
    (0..3).all(|i| a.0[i] < b.1[i] - 1e-9 && b.0[i] < a.1[i] - 1e-9)
}
