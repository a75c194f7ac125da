//! A new kind of dataset, added from outside the crate: a type implementing
//! `specular::io::Dataset` (one file; no registry line is needed to use it
//! from code, `pipeline::registry::dataset` is only for the command line)
//! runs through the pipelines like the built-in kinds.
//!
//! The dataset here makes its frames on demand (as a decoder of some other
//! format would) and counts how often it is asked, so the tests also check
//! the contract the pipelines keep with every dataset: frames it makes are
//! kept within the cache budget, and the results equal those on the same
//! frames held in memory.

use std::borrow::Cow;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use nalgebra::Isometry3;
use specular::cloud::Frame;
use specular::config::Config;
use specular::io::{Dataset, FrameEntry};
use specular::pipeline::{run_plane_optimized, Sequence};
use specular::sim::{self, Scene};

/// Frames "decoded" on demand from a store of simulated ones: every call
/// of `frame` hands out a fresh copy and is counted.
struct OnDemand {
    entries: Vec<FrameEntry>,
    store: Vec<Frame>,
    poses: Option<Vec<Isometry3<f64>>>,
    made: Arc<AtomicUsize>,
}

impl OnDemand {
    fn new(scene: &str, frames: usize, with_poses: bool) -> Self {
        let scene = Scene::resolve(scene).unwrap();
        let run = sim::simulate(&scene, Some(frames), None).unwrap();
        let entries = run
            .frames
            .iter()
            .map(|f| FrameEntry {
                path: format!("on-demand/{}", f.name).into(),
                name: f.name.clone(),
                stamp: f.stamp,
            })
            .collect();
        Self {
            entries,
            store: run.frames,
            poses: with_poses.then(|| run.poses.iter().map(|p| p.pose).collect()),
            made: Arc::new(AtomicUsize::new(0)),
        }
    }
}

impl Dataset for OnDemand {
    fn entries(&self) -> &[FrameEntry] {
        &self.entries
    }
    fn frame(&self, index: usize) -> specular::Result<Cow<'_, Frame>> {
        self.made.fetch_add(1, Ordering::Relaxed);
        Ok(Cow::Owned(self.store[index].clone()))
    }
    fn poses(&self) -> Option<Vec<Isometry3<f64>>> {
        self.poses.clone()
    }
    fn origin(&self) -> String {
        "on-demand".into()
    }
}

/// The plane-optimized pipeline on the custom dataset gives exactly what
/// it gives on the same frames held in memory, with the dataset's poses.
#[test]
fn a_custom_dataset_runs_through_the_plane_optimized_pipeline() {
    let config = Config::default();
    let dataset = OnDemand::new("office", 8, true);
    let made = dataset.made.clone();
    let held = Sequence::from_frames(
        dataset.store.clone(),
        dataset.poses.clone(),
        "held in memory",
    )
    .unwrap();
    let custom = Sequence::new(dataset);
    assert_eq!(custom.len(), 8);
    assert!(
        custom.poses.is_some(),
        "the dataset's poses are the sequence's"
    );
    assert!(custom.in_memory().is_none());

    let ours = run_plane_optimized(&custom, &config).unwrap();
    let reference = run_plane_optimized(&held, &config).unwrap();
    assert!(
        made.load(Ordering::Relaxed) >= 8,
        "every frame was asked for"
    );
    assert!(
        !ours.map.landmarks.is_empty(),
        "the office has reflective planes"
    );
    assert_eq!(ours.map.landmarks.len(), reference.map.landmarks.len());
    assert_eq!(ours.run.frames.len(), 8);
    for (a, b) in ours.run.frames.iter().zip(&reference.run.frames) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.classes, b.classes, "frame {}", a.name);
    }
    assert_eq!(
        ours.run.confusion.map(|c| c.metrics().accuracy),
        reference.run.confusion.map(|c| c.metrics().accuracy)
    );
}

/// Frames a dataset makes are kept between passes within the cache
/// budget: with the default budget two passes make each frame once, with
/// none every pass makes every frame again.
#[test]
fn frames_a_dataset_makes_are_cached_within_the_budget() {
    let count_two_passes = |cache_mb: Option<f64>| {
        let dataset = OnDemand::new("demo", 5, false);
        let made = dataset.made.clone();
        let mut sequence = Sequence::new(dataset);
        if let Some(mb) = cache_mb {
            sequence = sequence.with_frame_cache(mb);
        }
        for _ in 0..2 {
            let mut seen = 0;
            sequence
                .stream_all(
                    "test",
                    |_, f| Ok(f.points.len()),
                    |_, f, n| {
                        assert_eq!(n, f.points.len());
                        seen += 1;
                        Ok(())
                    },
                )
                .unwrap();
            assert_eq!(seen, 5);
        }
        made.load(Ordering::Relaxed)
    };
    assert_eq!(count_two_passes(None), 5);
    assert_eq!(count_two_passes(Some(0.0)), 10);
}

/// Without poses from the dataset (or a pose file) the plane-optimized
/// method refuses to run, saying what is missing.
#[test]
fn a_dataset_without_poses_is_refused_by_the_plane_optimized_method() {
    let sequence = Sequence::new(OnDemand::new("demo", 3, false));
    assert!(sequence.poses.is_none());
    let err = run_plane_optimized(&sequence, &Config::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("pose"), "{err}");
}
