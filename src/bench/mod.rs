//! The held-out benchmark: the plane-optimized pipeline (true poses) and
//! Reflection SLAM over seeds of every scene family, summarised per family
//! and over all by the median, the 10th percentile and the worst seed.
//!
//! This is the measuring stick of the method's generalisation: parameters
//! are chosen on the development split (seeds 0-999) only, and the
//! held-out split (seeds from 1,000,000) is reported and never tuned to
//! (`docs/benchmark.md`). Every figure comes from one command,
//! `specular bench families`.
//!
//! | module | job |
//! |---|---|
//! | this one | what to run ([`BenchSpec`]) and one seed's scores ([`SeedResult`]) |
//! | [`summary`] | median, 10th percentile and worst per family, the Markdown table |
//!
//! The calibration of the per-point confidences is summed over every seed
//! ([`reliability`]): one reliability diagram per benchmark.

pub mod summary;

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::classify::Class;
use crate::config::Config;
use crate::eval::{trajectory_error, Reliability};
use crate::pipeline::registry::{self, DatasetSource};
use crate::pipeline::{run_plane_optimized, run_slam, Sequence};
use crate::sim::family::Split;
use crate::sim::{LabelRule, SceneSource};
use crate::Result;

pub use summary::{FamilySummary, Stat, Summary, METRICS};

/// The calibration counts of every seed in `results`, summed.
pub fn reliability(results: &[SeedResult]) -> Reliability {
    let mut all = Reliability::default();
    for r in results {
        all.merge(&r.reliability);
    }
    all
}

/// Frames per sequence of the full benchmark: 20 s at 10 Hz.
pub const DEFAULT_FRAMES: usize = 200;
/// Seeds per family of the full benchmark.
pub const DEFAULT_SEEDS: usize = 10;

/// What one benchmark run covers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchSpec {
    /// Families, by name.
    pub families: Vec<String>,
    /// Development or held-out seeds.
    #[serde(with = "split_name")]
    pub split: Split,
    /// Seeds per family (the first of the split).
    pub seeds: usize,
    /// Frames per sequence.
    pub frames: usize,
    /// Whether Reflection SLAM runs too (for the ATE).
    pub slam: bool,
}

impl BenchSpec {
    /// Every (family, seed) pair, family by family.
    pub fn runs(&self) -> Vec<(String, u64)> {
        self.families
            .iter()
            .flat_map(|f| {
                self.split
                    .seeds(self.seeds)
                    .into_iter()
                    .map(move |s| (f.clone(), s))
            })
            .collect()
    }
}

/// The scores of one sequence, in percent (ATE in metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedResult {
    /// The family.
    pub family: String,
    /// The seed.
    pub seed: u64,
    /// Frames run.
    pub frames: usize,
    /// Mean IoU of the four classes (of those present in the truth).
    pub miou: f64,
    /// Share of true reflections called Reflection or left unclassified.
    pub reflection_removal: f64,
    /// IoU of obstacles behind glass (NaN when the truth has none).
    pub obstacle_iou: f64,
    /// Recall of normal points.
    pub normal_recall: f64,
    /// IoU of the reflective surface (glass and mirror).
    pub glass_iou: f64,
    /// Reflection SLAM's absolute trajectory error (RMSE after SE(3)
    /// alignment), metres; `None` without SLAM.
    pub ate: Option<f64>,
    /// Points scored.
    pub points: u64,
    /// True reflections among them: what the reflection removal is a
    /// share of (a handful of points makes it a coin toss).
    #[serde(default)]
    pub reflections: u64,
    /// Wall time of the sequence (simulation, both pipelines), seconds.
    pub seconds: f64,
    /// The calibration counts of the plane-optimized pipeline's
    /// confidences (empty when it gives none). Not written per seed: the
    /// benchmark writes them summed over all seeds
    /// ([`Reliability::merge`]).
    #[serde(skip)]
    pub reliability: Reliability,
}

impl SeedResult {
    /// The value of metric `name` ([`METRICS`]).
    pub fn metric(&self, name: &str) -> f64 {
        match name {
            "miou" => self.miou,
            "reflection_removal" => self.reflection_removal,
            "obstacle_iou" => self.obstacle_iou,
            "normal_recall" => self.normal_recall,
            "glass_iou" => self.glass_iou,
            "ate" => self.ate.unwrap_or(f64::NAN),
            _ => f64::NAN,
        }
    }
}

/// Run the plane-optimized pipeline with the true poses, and Reflection
/// SLAM when `slam`, on `frames` frames of `family`'s scene for `seed`,
/// scored against 3DRef's labelling rule.
pub fn run_seed(
    family: &str,
    seed: u64,
    frames: usize,
    slam: bool,
    config: &Config,
) -> Result<SeedResult> {
    let started = Instant::now();
    let source = DatasetSource::Simulated {
        scene: SceneSource::Family {
            family: family.to_string(),
            seed,
        },
        frames: Some(frames),
        seed: None,
        labels: LabelRule::Raycast3dref,
        sensor: None,
    };
    let mut sequence = Sequence::from_dataset(registry::dataset(&source)?)
        .with_frame_cache(config.input.frame_cache_mb);
    let out = run_plane_optimized(&sequence, config)?;
    let m = out.run.confusion.map(|c| c.metrics()).ok_or_else(|| {
        crate::Error::Input(format!("{family}/{seed}: the frames carry no labels"))
    })?;
    let ate = if slam {
        let truth = sequence.poses.take().unwrap_or_default();
        let estimate = run_slam(&sequence, config, truth.first().copied())?;
        Some(trajectory_error(&estimate.poses, &truth, config.slam.rpe_segment)?.ate_rmse)
    } else {
        None
    };
    Ok(SeedResult {
        family: family.to_string(),
        seed,
        frames,
        miou: m.miou,
        reflection_removal: m.reflection_removal,
        obstacle_iou: m.class(Class::Obstacle).iou,
        normal_recall: m.class(Class::Normal).recall,
        glass_iou: m.class(Class::Glass).iou,
        ate,
        points: m.points,
        reflections: m.class(Class::Reflection).truth,
        seconds: started.elapsed().as_secs_f64(),
        reliability: out.run.reliability.unwrap_or_default(),
    })
}

/// Serde of a [`Split`] by its name.
mod split_name {
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::sim::family::Split;

    pub fn serialize<S: Serializer>(split: &Split, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(split.name())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Split, D::Error> {
        let name = String::deserialize(d)?;
        match name.as_str() {
            "development" => Ok(Split::Development),
            "held-out" => Ok(Split::HeldOut),
            other => Err(serde::de::Error::custom(format!("unknown split '{other}'"))),
        }
    }
}
