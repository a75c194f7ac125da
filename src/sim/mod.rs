//! A dual-return LiDAR simulator with glass and mirrors.
//!
//! The simulator produces labelled 3DRef-style sequences with exact ground
//! truth (poses, reflective planes, the label of every return), so every
//! stage of specular can be tested and benchmarked without recording data.
//!
//! | module | job |
//! |---|---|
//! | [`scene`] | the TOML scene format: materials, rooms, walls, boxes, sensor, trajectory |
//! | [`surface`] | planar polygons, their plane and triangulation |
//! | [`material`] | surface echo, reflectance and transmittance versus incidence angle |
//! | [`trajectory`] | waypoints at constant speed with a smoothed heading |
//! | [`raycast`] | BVH ray casting over the triangulated surfaces (parry) |
//! | [`echo`] | beam physics: surface echoes, transmitted and specular rays, labels |
//! | [`returns`] | merging echoes, detection, first/strongest + last selection |
//! | [`labels`] | the label of a point: 3DRef's ray-cast rule, or the echo's physical path |
//! | [`simulator`] | one frame: every beam of the pattern, noise, points |
//! | [`truth`] | ground-truth reflective planes (`planes.json`) |
//! | [`stats`] | label shares of a sequence |
//! | [`builtin`] | the scenes of `datasets/scenes/`, embedded |
//! | [`family`] | scene families: random buildings of one kind from a seed, development and held-out splits |
//! | [`dataset`] | the simulator as a [`Dataset`](crate::io::Dataset), frames made on demand |
//!
//! The physics follows the paper's "Sensor Modeling" section: at glass a
//! beam produces a surface echo that is strong only near normal incidence, a
//! transmitted ray that may hit an obstacle behind the glass, and a specular
//! ray whose echo the sensor reports along the original beam direction at
//! the full path length, i.e. behind the glass. Mirrors reflect almost all
//! light. A point is labelled by 3DRef's own ray-cast rule ([`labels`]),
//! as the real data is; the physical path of its echo stays in its
//! [`PointTruth`].
//!
//! Simplifications: by default the whole revolution is taken at one pose
//! (no motion distortion within a sweep; `[sensor] sweep = true` fires the
//! beams over the period while the sensor moves), beams have no divergence (no mixed pixels at
//! edges), and the sensor is upright (yaw only).
//!
//! ```
//! use specular::sim::{simulate, Scene};
//! let scene = Scene::resolve("demo")?;
//! let run = simulate(&scene, Some(5), None)?;
//! assert_eq!(run.frames.len(), 5);
//! # Ok::<(), specular::Error>(())
//! ```

pub mod builtin;
pub mod dataset;
pub mod echo;
pub mod family;
pub mod labels;
pub mod material;
pub mod raycast;
pub mod returns;
pub mod scene;
pub mod simulator;
pub mod stats;
pub mod surface;
pub mod trajectory;
pub mod truth;

use rayon::prelude::*;

pub use dataset::SimDataset;
pub use echo::{label, Echo};
pub use labels::LabelRule;
pub use material::{Material, MaterialKind};
pub use scene::{Scene, SceneChanges};
pub use simulator::{frame_seed, PointTruth, SimFrame, Simulator};
pub use stats::{LabelCounts, LabelShares};
pub use truth::{PlaneTally, TruePlanes};

use crate::cloud::Frame;
use crate::io::{PlaneRecord, StampedPose};
use crate::{Error, Result};

/// Most frames one run may ask for (about a day at 10 Hz).
pub const MAX_FRAMES: usize = 1_000_000;

/// Where a simulated scene comes from: a built-in name or a scene file, or
/// a family drawn with a seed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SceneSource {
    /// A built-in scene ([`builtin::names`]) or a scene TOML file.
    Named(String),
    /// The scene of a [`family`] for a seed.
    Family {
        /// The family's name ([`family::names`]).
        family: String,
        /// Its seed (development below 1000, held out from 1,000,000).
        seed: u64,
    },
}

impl SceneSource {
    /// The scene, loaded or drawn.
    pub fn resolve(&self) -> Result<Scene> {
        match self {
            SceneSource::Named(name) => Scene::resolve(name),
            SceneSource::Family { family, seed } => Ok(family::generate(family, *seed)?.scene),
        }
    }

    /// The scene with its sensor model replaced by `sensor` when given
    /// (`--sensor ouster-os0-128`), and the scene file to write beside its
    /// frames: a family's (drawn) or a changed one's; `None` for a named
    /// scene as it is.
    pub fn resolve_for(&self, sensor: Option<&str>) -> Result<(Scene, Option<String>)> {
        self.resolve_with(&SceneChanges {
            sensor: sensor.map(str::to_string),
            ..Default::default()
        })
    }

    /// The scene with `changes` made to it (`simulate --sensor X --sweep
    /// --speed 1 --turn-rate 45`), and the scene file to write beside its
    /// frames: a family's (drawn) or a changed one's; `None` for a named
    /// scene as it is.
    pub fn resolve_with(&self, changes: &SceneChanges) -> Result<(Scene, Option<String>)> {
        let unchanged = changes.is_empty();
        let (text, origin) = match self {
            SceneSource::Named(name) if unchanged => return Ok((Scene::resolve(name)?, None)),
            SceneSource::Named(name) => Scene::text_of(name)?,
            SceneSource::Family { family, seed } => {
                let generated = family::generate(family, *seed)?;
                if unchanged {
                    return Ok((generated.scene, Some(generated.toml)));
                }
                let origin = std::path::PathBuf::from(format!("family:{family}/{seed}"));
                (generated.toml, origin)
            }
        };
        let (scene, toml) = Scene::with_changes(&text, &origin, changes)?;
        Ok((scene, Some(toml)))
    }
}

impl std::fmt::Display for SceneSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneSource::Named(name) => f.write_str(name),
            SceneSource::Family { family, seed } => write!(f, "{family}/{seed}"),
        }
    }
}

/// A simulated sequence in memory.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The frames, in time order.
    pub frames: Vec<Frame>,
    /// True poses `T_world_sensor`, one per frame.
    pub poses: Vec<StampedPose>,
    /// True reflective planes (`planes.json`).
    pub planes: Vec<PlaneRecord>,
    /// Per-point truth (scattering surface, reflecting surface), parallel
    /// to each frame's points.
    pub truth: Vec<Vec<PointTruth>>,
}

/// Simulate `frames` frames of `scene` (default: the scene's count) with
/// `seed` (default: the scene's seed), in memory and in parallel.
///
/// The result does not depend on the number of threads.
pub fn simulate(scene: &Scene, frames: Option<usize>, seed: Option<u64>) -> Result<Simulation> {
    let n = frames.unwrap_or(scene.frames);
    check_frames(n)?;
    let seed = seed.unwrap_or(scene.seed);
    let sim = Simulator::new(scene);
    let planes = TruePlanes::of(scene);
    let sims: Vec<SimFrame> = (0..n).into_par_iter().map(|k| sim.frame(k, seed)).collect();
    let mut tally = PlaneTally::default();
    for (k, f) in sims.iter().enumerate() {
        tally.add(k, &planes.observed_in(f));
    }
    let records = planes.records(scene, &tally, |k| sim.stamp(k).0);
    let mut out = Simulation {
        frames: Vec::with_capacity(n),
        poses: Vec::with_capacity(n),
        planes: records,
        truth: Vec::with_capacity(n),
    };
    for f in sims {
        out.frames.push(f.frame);
        out.poses.push(f.pose);
        out.truth.push(f.truth);
    }
    Ok(out)
}

/// Check a requested frame count.
pub fn check_frames(n: usize) -> Result<()> {
    if n == 0 || n > MAX_FRAMES {
        return Err(Error::Input(format!(
            "the number of frames must be in 1..={MAX_FRAMES}, got {n}"
        )));
    }
    Ok(())
}
