//! Writing a run's outputs as its frames are classified, so a sequence of
//! any length is written without holding its classes: predictions, the
//! world maps and the recording grow a frame at a time; the summaries
//! (metrics, planes, report) are written when the run has succeeded.
//!
//! Per frame, `predictions/<stem>.label` (the classes), `<stem>.rule`
//! (with `--rules`) and `<stem>.prob` (each class's confidence, one
//! little-endian `f32` per input point, when the method gives one).
//!
//! Nothing is left behind by a run that fails: predictions go to
//! `predictions.partial/` and replace `predictions/` only at the end, the
//! recording to `run.mcap.tmp`, and both are removed on error.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::Isometry3;
use specular::cloud::Frame;
use specular::config::Config;
use specular::io::{self, MapPoint};
use specular::pipeline::plane_optimized::{AroundCornerMap, MeasuredMap};
use specular::pipeline::{FrameOutput, FrameSink, PlaneOptimizedOutput, RunOutput};
use specular::reflect::BoundedPlane;
use specular::viz::{McapRecorder, McapSummary};

/// Which outputs a run writes besides predictions and scores.
#[derive(Debug, Clone, Default)]
pub(crate) struct OutputOptions {
    /// The around-the-corner map (methods with a plane map).
    pub around_corner: bool,
    /// The outputs for people: `map.ply`, plots, report (and `run.mcap`
    /// when `mcap`).
    pub visual: bool,
    /// `run.mcap` (with `visual`).
    pub mcap: bool,
    /// Beside each `.label` file, a `.rule` file: per point, the id of the
    /// rule that decided its class (`specular::classify::Rule`), in the
    /// same format (little-endian u32 per point).
    pub rules: bool,
}

/// The [`FrameSink`] of the command-line tool: writes each frame's
/// predictions and adds it to the maps and the recording.
pub(crate) struct RunWriter {
    out: PathBuf,
    partial: PathBuf,
    created_out: bool,
    config: Config,
    options: OutputOptions,
    around: Option<AroundCornerMap>,
    measured: Option<MeasuredMap>,
    recorder: Option<McapRecorder>,
    trajectory: Vec<[f64; 3]>,
    finished: bool,
}

/// What the frame-by-frame outputs came to, for the summaries.
pub(crate) struct WrittenFrames {
    /// The around-the-corner map, when built.
    pub around_corner: Option<Vec<MapPoint>>,
    /// The classified map as measured, when built.
    pub measured: Option<Vec<MapPoint>>,
    /// The recording, when written.
    pub mcap: Option<McapSummary>,
    /// The sensor path (x, y, z), when the frames had poses.
    pub trajectory: Vec<[f64; 3]>,
}

impl RunWriter {
    /// A writer into `out` (created when missing).
    pub(crate) fn new(out: &Path, config: &Config, options: OutputOptions) -> Result<Self> {
        let created_out = !out.exists();
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let partial = out.join("predictions.partial");
        if partial.exists() {
            std::fs::remove_dir_all(&partial)
                .with_context(|| format!("removing {}", partial.display()))?;
        }
        Ok(Self {
            out: out.to_path_buf(),
            partial,
            created_out,
            config: config.clone(),
            options,
            around: None,
            measured: None,
            recorder: None,
            trajectory: Vec::new(),
            finished: false,
        })
    }

    /// Move the predictions into place and close the maps and the
    /// recording.
    pub(crate) fn finish(mut self) -> Result<WrittenFrames> {
        let predictions = self.out.join("predictions");
        if predictions.exists() {
            std::fs::remove_dir_all(&predictions)
                .with_context(|| format!("removing the old {}", predictions.display()))?;
        }
        if self.partial.exists() {
            std::fs::rename(&self.partial, &predictions)
                .with_context(|| format!("moving predictions into {}", predictions.display()))?;
        }
        let mcap = match self.recorder.take() {
            Some(r) => Some(r.finish()?),
            None => None,
        };
        self.finished = true;
        Ok(WrittenFrames {
            around_corner: self.around.take().map(AroundCornerMap::into_points),
            measured: self.measured.take().map(MeasuredMap::into_points),
            mcap,
            trajectory: std::mem::take(&mut self.trajectory),
        })
    }
}

impl FrameSink for RunWriter {
    fn begin(&mut self, planes: &[BoundedPlane]) -> specular::Result<()> {
        let voxel = self.config.output.map_voxel;
        let margin = self.config.plane_map.hull_margin;
        if self.options.around_corner {
            self.around = Some(AroundCornerMap::new(planes, margin, voxel));
        }
        if self.options.visual {
            self.measured = Some(MeasuredMap::new(voxel));
            if self.options.mcap {
                self.recorder = Some(McapRecorder::create(
                    &self.out.join("run.mcap"),
                    planes,
                    margin,
                )?);
            }
        }
        std::fs::create_dir_all(&self.partial).map_err(|e| specular::Error::io(&self.partial, e))
    }

    fn frame(
        &mut self,
        _index: usize,
        frame: &Frame,
        pose: Option<&Isometry3<f64>>,
        output: FrameOutput,
    ) -> specular::Result<()> {
        // After Ctrl-C nothing more is written (the handler is removing
        // the partial predictions).
        if super::run_dir::interrupted() {
            return Err(specular::Error::Input("interrupted".into()));
        }
        // One entry per input point: 0 where the reader set a point aside.
        let ids = output.input_class_ids();
        io::write_labels(&self.partial.join(format!("{}.label", output.name)), &ids)?;
        if self.options.rules {
            let rules = output.input_rule_ids();
            io::write_labels(&self.partial.join(format!("{}.rule", output.name)), &rules)?;
        }
        // The confidence of each class, when the method says one (0 where
        // a point was set aside).
        if !output.confidence.is_empty() {
            let probs = output.input_confidence();
            io::write_probs(&self.partial.join(format!("{}.prob", output.name)), &probs)?;
        }
        if let Some(pose) = pose {
            self.trajectory.push(pose.translation.vector.into());
            let confidence = &output.confidence;
            if let Some(map) = &mut self.around {
                map.add(frame, pose, &output.classes, confidence);
            }
            if let Some(map) = &mut self.measured {
                map.add(frame, pose, &output.classes, confidence);
            }
            if let Some(recorder) = &mut self.recorder {
                recorder.add(frame, pose, &output.classes, &output.rules, confidence)?;
            }
        }
        Ok(())
    }
}

impl Drop for RunWriter {
    /// A run that did not finish leaves no predictions (the recorder
    /// removes its own temporary file), and no directory it created.
    fn drop(&mut self) {
        if !self.finished {
            self.recorder = None;
            let _ = std::fs::remove_dir_all(&self.partial);
            if self.created_out {
                let _ = std::fs::remove_dir(&self.out);
            }
        }
    }
}

/// Write the summaries of a finished run into `out`: the configuration,
/// the metrics (when labelled) with the rule tally, the number of input
/// points dropped as non-finite (`dropped_non_finite_points`) and the
/// calibration of the confidences (`reliability`, when the method gives
/// them), and, with a
/// plane map,
/// `planes.json` and `around_corner.ply`.
pub(crate) fn write_summaries(
    out: &Path,
    config: &Config,
    names: &[String],
    run: &RunOutput,
    map: Option<&PlaneOptimizedOutput>,
    written: &WrittenFrames,
) -> Result<()> {
    io::write_atomic(&out.join("config.toml"), |w| {
        std::io::Write::write_all(w, config.to_toml().as_bytes())
    })?;
    if let Some(map) = map {
        let records: Vec<_> = map
            .used
            .iter()
            .zip(&map.planes)
            .map(|(&i, bp)| map.map.landmarks[i].record(bp, names))
            .collect();
        io::write_planes(&out.join("planes.json"), &records)?;
    }
    if let Some(points) = &written.around_corner {
        io::write_map_ply(&out.join("around_corner.ply"), points)?;
    }
    if let Some(conf) = &run.confusion {
        // The scores, and which rule decided how many points of each label.
        let mut value = serde_json::to_value(conf.metrics()).context("serialising metrics")?;
        if let Some(obj) = value.as_object_mut() {
            obj.insert("specular".into(), specular::provenance());
            obj.insert(
                "rules".into(),
                serde_json::to_value(run.rules).context("serialising rules")?,
            );
            obj.insert(
                "dropped_non_finite_points".into(),
                run.dropped_non_finite.into(),
            );
            // How far the confidences are to be trusted (when the method
            // gives them).
            if let Some(r) = &run.reliability {
                obj.insert(
                    "reliability".into(),
                    serde_json::to_value(r.report()).context("serialising reliability")?,
                );
            }
        }
        let json = serde_json::to_string_pretty(&value).context("serialising metrics")?;
        io::write_atomic(&out.join("metrics.json"), |w| {
            std::io::Write::write_all(w, json.as_bytes())
        })?;
    } else {
        // Without labels: what was predicted, and by which rule.
        let value = serde_json::json!({
            "specular": specular::provenance(),
            "labelled": false,
            "predicted": predicted_counts(run)
                .into_iter()
                .map(|(class, n)| (class.to_string(), serde_json::Value::from(n)))
                .collect::<serde_json::Map<_, _>>(),
            "rules": serde_json::to_value(run.rules).context("serialising rules")?,
            "dropped_non_finite_points": run.dropped_non_finite,
        });
        let json = serde_json::to_string_pretty(&value).context("serialising metrics")?;
        io::write_atomic(&out.join("metrics.json"), |w| {
            std::io::Write::write_all(w, json.as_bytes())
        })?;
    }
    Ok(())
}

/// Points predicted per class (by class name), in the classes' id order.
pub(crate) fn predicted_counts(run: &RunOutput) -> Vec<(&'static str, u64)> {
    use specular::classify::Class;
    [
        Class::Normal,
        Class::Glass,
        Class::Reflection,
        Class::Obstacle,
        Class::Unclassified,
    ]
    .into_iter()
    .map(|c| (c.name(), run.rules.predicted(c)))
    .collect()
}
