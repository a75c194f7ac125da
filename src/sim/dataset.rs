//! The simulator as a [`Dataset`]: frames made one at a time when a pass
//! asks for them, with the true poses and the scene's sensor model, so a
//! long simulated sequence needs no more memory than a recorded one.

use std::borrow::Cow;

use nalgebra::Isometry3;

use super::{check_frames, LabelRule, Scene, Simulator};
use crate::cloud::Frame;
use crate::io::{Dataset, FrameEntry};
use crate::sensor::SensorModel;
use crate::Result;

/// `frames` frames of a scene, simulated on demand with one seed. Frame
/// `k` depends only on (scene, `k`, seed): the same bytes in any order,
/// the same as [`simulate`](super::simulate) makes.
#[derive(Debug)]
pub struct SimDataset {
    sim: Simulator,
    seed: u64,
    origin: String,
    entries: Vec<FrameEntry>,
}

impl SimDataset {
    /// `frames` frames of `scene` (default: the scene's count) with `seed`
    /// (default: the scene's). Entries are named `sim:<name>/<stamp>.ply`.
    pub fn new(scene: &Scene, frames: Option<usize>, seed: Option<u64>) -> Result<Self> {
        let n = frames.unwrap_or(scene.frames);
        check_frames(n)?;
        let sim = Simulator::new(scene);
        let origin = format!("sim:{}", scene.name);
        let entries = (0..n)
            .map(|k| {
                let (name, stamp) = sim.stamp(k);
                FrameEntry {
                    path: std::path::Path::new(&origin).join(format!("{name}.ply")),
                    name,
                    stamp,
                }
            })
            .collect();
        Ok(Self {
            seed: seed.unwrap_or(scene.seed),
            sim,
            origin,
            entries,
        })
    }

    /// The same frames labelled by `rule` (default: 3DRef's ray-cast rule).
    pub fn with_label_rule(mut self, rule: LabelRule) -> Self {
        self.sim = self.sim.with_label_rule(rule);
        self
    }
}

impl Dataset for SimDataset {
    fn entries(&self) -> &[FrameEntry] {
        &self.entries
    }

    fn frame(&self, index: usize) -> Result<Cow<'_, Frame>> {
        Ok(Cow::Owned(self.sim.frame(index, self.seed).frame))
    }

    fn poses(&self) -> Option<Vec<Isometry3<f64>>> {
        Some((0..self.len()).map(|k| self.sim.pose(k).pose).collect())
    }

    fn sensor(&self) -> Option<SensorModel> {
        Some(self.sim.scene().sensor.model.clone())
    }

    fn origin(&self) -> String {
        self.origin.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Made one at a time, in any order, the frames and poses are the
    /// simulation's; the sensor is the scene's.
    #[test]
    fn frames_on_demand_equal_the_simulation() {
        let scene = Scene::resolve("demo").unwrap();
        let run = super::super::simulate(&scene, Some(3), Some(7)).unwrap();
        let dataset = SimDataset::new(&scene, Some(3), Some(7)).unwrap();
        assert_eq!(dataset.len(), 3);
        for k in [2, 0, 1] {
            let frame = dataset.frame(k).unwrap();
            assert_eq!(frame.name, run.frames[k].name);
            assert_eq!(dataset.entries()[k].name, run.frames[k].name);
            assert_eq!(frame.points, run.frames[k].points);
        }
        let poses: Vec<_> = run.poses.iter().map(|p| p.pose).collect();
        assert_eq!(dataset.poses(), Some(poses));
        assert_eq!(dataset.sensor(), Some(scene.sensor.model.clone()));
        assert!(SimDataset::new(&scene, Some(0), None).is_err());
    }
}
