//! Name → implementation: the one place where configuration picks the
//! implementations of the seams.

use std::path::PathBuf;
use std::sync::Arc;

use crate::classify::{Classifier, PlaneMapClassifier, SingleScanClassifier};
use crate::config::Config;
use crate::frontend::{ExtractorName, PlaneExtractor, RegionGrowingExtractor};
use crate::io::{BagOptions, Dataset, PlyDir, Ros2Bag};
use crate::map::{MapMerger, MergerName, WeightedAverageMerger};
use crate::reflect::{CandidateRansacDetector, ReflectiveDetector};
use crate::registration::{AcceptAll, GroundTripleRansac, MismatchRejector, RejectorName};
use crate::sensor::SensorModel;
use crate::sim::{LabelRule, SceneSource, SimDataset};
use crate::Result;

/// The kinds of [`Dataset`] chosen by name on the command line (a new
/// kind: a type implementing [`Dataset`], a variant here and its arm in
/// [`dataset`]).
#[derive(Debug, Clone, PartialEq)]
pub enum DatasetSource {
    /// A 3DRef frame directory or release sequence ([`PlyDir`]).
    Frames(PathBuf),
    /// The `PointCloud2` topic of a ROS 2 bag ([`Ros2Bag`]).
    Bag {
        /// rosbag2 directory, `.mcap` or `.db3` file.
        path: PathBuf,
        /// The point-cloud topic.
        topic: String,
        /// The drivers' layout and Ouster's second-return topic.
        options: BagOptions,
    },
    /// A simulated scene, made frame by frame ([`SimDataset`]).
    Simulated {
        /// Built-in scene, scene file or family and seed.
        scene: SceneSource,
        /// Number of frames (default: the scene's).
        frames: Option<usize>,
        /// Range-noise seed (default: the scene's).
        seed: Option<u64>,
        /// Which truth the labels carry (default: 3DRef's ray-cast rule).
        labels: LabelRule,
        /// The sensor model instead of the scene's (a built-in name or a
        /// sensor file).
        sensor: Option<String>,
    },
}

/// The dataset `source` names, opened (a directory listed, a bag decoded,
/// a scene loaded); frames are read through it pass by pass.
pub fn dataset(source: &DatasetSource) -> Result<Arc<dyn Dataset>> {
    Ok(match source {
        DatasetSource::Frames(dir) => Arc::new(PlyDir::open(dir)?),
        DatasetSource::Bag {
            path,
            topic,
            options,
        } => Arc::new(Ros2Bag::open_with(path, topic, options)?),
        DatasetSource::Simulated {
            scene,
            frames,
            seed,
            labels,
            sensor,
        } => {
            let (scene, _) = scene.resolve_for(sensor.as_deref())?;
            Arc::new(SimDataset::new(&scene, *frames, *seed)?.with_label_rule(*labels))
        }
    })
}

/// The reflective detector named in `[detector]`.
pub fn detector(config: &Config, sensor: &SensorModel) -> Box<dyn ReflectiveDetector> {
    Box::new(CandidateRansacDetector::new(
        config.detector,
        sensor.clone(),
    ))
}

/// The single-scan classifier configured in `[single_scan]`.
pub fn single_scan_classifier(config: &Config) -> Box<dyn Classifier> {
    Box::new(SingleScanClassifier::new(config.single_scan))
}

/// The plane-map classifier configured in `[plane_map]` (an unknown
/// evidence test in `plane_map.weighing.tests` is an error).
pub fn plane_map_classifier(config: &Config) -> crate::Result<PlaneMapClassifier> {
    PlaneMapClassifier::new(config.plane_map.clone())
}

/// The map merger of [`crate::map::MapParams::merger`] (the weighted
/// average; no key).
pub fn merger(config: &Config) -> Box<dyn MapMerger> {
    match config.map.merger {
        MergerName::WeightedAverage => Box::new(WeightedAverageMerger::new(config.map.merge)),
    }
}

/// The plane extractor of [`crate::frontend::ExtractorParams::name`]
/// (region growing; no key).
pub fn extractor(config: &Config) -> Box<dyn PlaneExtractor> {
    match config.extractor.name {
        ExtractorName::RegionGrowing => Box::new(RegionGrowingExtractor::new(config.extractor)),
    }
}

/// The mismatch rejector of [`crate::registration::RejectorParams::name`]
/// (the ground-constrained triple RANSAC; no key).
pub fn rejector(config: &Config) -> Box<dyn MismatchRejector> {
    match config.slam.rejector.name {
        RejectorName::GroundTripleRansac => Box::new(GroundTripleRansac::new(config.slam.rejector)),
        RejectorName::None => Box::new(AcceptAll::new(config.slam.rejector)),
    }
}

/// A per-frame seed derived from the run seed and the frame's name, so a
/// frame's result does not depend on which other frames are processed.
pub fn frame_seed(seed: u64, name: &str) -> u64 {
    // FNV-1a over the name, mixed with the seed.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ seed;
    for b in name.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
