//! `run.mcap`: a run as a Foxglove recording (protobuf, the `foxglove.*`
//! schemas), written with the official `foxglove` SDK through a private
//! [`Context`], so concurrent runs never mix messages.
//!
//! | topic | schema | per frame |
//! |---|---|---|
//! | `/cloud` | `foxglove.PointCloud` | the frame in the `map` frame: `x y z` f32, `class` u8 (prediction id), `intensity` f32, `rule` u8 (which rule decided the class, `classify::Rule`), `confidence` f32 (the probability that the class is right; NaN where the method gives none) |
//! | `/mirrored` | `foxglove.PointCloud` | the frame's reflections mirrored back through their plane (`map` frame) |
//! | `/planes` | `foxglove.SceneUpdate` | each reflective landmark: translucent hull and panes, outlined |
//! | `/tf` | `foxglove.FrameTransform` | `map` → `lidar` (the sensor pose) |
//! | `/trajectory` | `foxglove.PosesInFrame` | the sensor poses up to this frame (`map` frame) |
//!
//! Log time is the frame timestamp.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use foxglove::messages::{
    line_primitive, packed_element_field::NumericType, Color, FrameTransform, LinePrimitive,
    PackedElementField, Point3 as FgPoint3, PointCloud, Pose, PosesInFrame, Quaternion,
    SceneEntity, SceneUpdate, Timestamp, TriangleListPrimitive, Vector3,
};
use foxglove::{Channel, ChannelBuilder, Context, McapWriter, McapWriterHandle};
use nalgebra::{Isometry3, Point3};

use crate::classify::mirror::mirror_reflections;
use crate::classify::{Class, Rule};
use crate::cloud::Frame;
use crate::pipeline::Sequence;
use crate::reflect::{planes_seen_from, BoundedPlane};
use crate::{Error, Result};

/// The world frame's id in the recording.
pub const WORLD_FRAME: &str = "map";
/// The sensor frame's id in the recording.
pub const SENSOR_FRAME: &str = "lidar";
/// Bytes per point on `/cloud`: x, y, z (f32), class (u8), intensity (f32),
/// rule (u8), confidence (f32).
const CLOUD_STRIDE: u32 = 22;
/// Bytes per point on `/mirrored`: x, y, z (f32), class (u8).
const MIRRORED_STRIDE: u32 = 13;

/// What goes into a recording: a sequence with poses, its classes and the
/// reflective planes (world frame).
#[derive(Debug, Clone, Copy)]
pub struct McapRun<'a> {
    /// The frames and their poses (`T_world_sensor`).
    pub sequence: &'a Sequence,
    /// One class per point, per frame.
    pub classes: &'a [Vec<Class>],
    /// The rule that decided each point, per frame (an empty vector where
    /// unknown: the field then reads 0, "undecided").
    pub rules: &'a [Vec<Rule>],
    /// The confidence of each point's class, per frame (an empty vector
    /// where unknown: the field then reads NaN).
    pub confidence: &'a [Vec<f32>],
    /// Reflective planes, world frame.
    pub planes: &'a [BoundedPlane],
    /// Hull margin used to mirror reflections back (metres).
    pub hull_margin: f64,
}

/// Message counts of a written recording.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct McapSummary {
    /// Frames recorded (one message per frame on every topic).
    pub frames: usize,
    /// Points on `/cloud`, all frames.
    pub cloud_points: usize,
    /// Points on `/mirrored`, all frames.
    pub mirrored_points: usize,
}

/// Write `run` as an MCAP file at `path` (replaced if it exists; written to
/// a temporary file and renamed into place). The sequence must carry poses.
pub fn write_run_mcap(path: &Path, run: &McapRun<'_>) -> Result<McapSummary> {
    let poses = run.sequence.poses.as_ref().ok_or_else(|| {
        Error::Input("an MCAP recording needs a pose per frame (--poses FILE)".into())
    })?;
    if run.classes.len() != run.sequence.len() || poses.len() != run.sequence.len() {
        return Err(Error::Input(format!(
            "{}: {} frames but {} class vectors and {} poses",
            path.display(),
            run.sequence.len(),
            run.classes.len(),
            poses.len()
        )));
    }
    let mut recorder = McapRecorder::create(path, run.planes, run.hull_margin)?;
    for (k, pose) in poses.iter().enumerate() {
        let rules = run.rules.get(k).map_or(&[][..], |r| r.as_slice());
        let confidence = run.confidence.get(k).map_or(&[][..], |c| c.as_slice());
        let frame = run.sequence.frame(k)?;
        recorder.add(&frame, pose, &run.classes[k], rules, confidence)?;
    }
    recorder.finish()
}

/// A recording written a frame at a time (to a temporary file beside
/// `path`, renamed into place by [`finish`](Self::finish) and removed when
/// the recorder is dropped unfinished), so a long run is recorded without
/// holding its frames.
pub struct McapRecorder {
    path: PathBuf,
    tmp: PathBuf,
    writer: Option<McapWriterHandle<BufWriter<File>>>,
    _context: Arc<Context>,
    cloud: Channel<PointCloud>,
    mirrored: Channel<PointCloud>,
    planes_channel: Channel<SceneUpdate>,
    tf: Channel<FrameTransform>,
    trajectory: Channel<PosesInFrame>,
    planes: Vec<BoundedPlane>,
    scene: SceneUpdate,
    hull_margin: f64,
    trail: Trail,
    summary: McapSummary,
}

impl McapRecorder {
    /// Start a recording at `path` against the reflective `planes` (world
    /// frame); `hull_margin` is used to mirror reflections back.
    pub fn create(path: &Path, planes: &[BoundedPlane], hull_margin: f64) -> Result<Self> {
        let tmp = tmp_path(path);
        let fox =
            |e: foxglove::FoxgloveError| Error::Input(format!("{}: MCAP: {e}", tmp.display()));
        let file = File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        let ctx = Context::new();
        let writer = McapWriter::new()
            .context(&ctx)
            .create(BufWriter::new(file))
            .map_err(fox)?;
        let channel = |topic: &str| ChannelBuilder::new(topic).context(&ctx);
        Ok(Self {
            path: path.to_path_buf(),
            tmp: tmp.clone(),
            writer: Some(writer),
            cloud: channel("/cloud").build::<PointCloud>(),
            mirrored: channel("/mirrored").build::<PointCloud>(),
            planes_channel: channel("/planes").build::<SceneUpdate>(),
            tf: channel("/tf").build::<FrameTransform>(),
            trajectory: channel("/trajectory").build::<PosesInFrame>(),
            _context: ctx,
            planes: planes.to_vec(),
            scene: scene_update(planes),
            hull_margin,
            trail: Trail::default(),
            summary: McapSummary::default(),
        })
    }

    /// Record one frame with its pose (`T_world_sensor`), classes, the
    /// rules that decided them and their confidences (either empty where
    /// unknown).
    pub fn add(
        &mut self,
        frame: &Frame,
        pose: &Isometry3<f64>,
        classes: &[Class],
        rules: &[Rule],
        confidence: &[f32],
    ) -> Result<()> {
        if classes.len() != frame.points.len() {
            return Err(Error::Input(format!(
                "{}: frame {} has {} points but {} classes",
                self.path.display(),
                frame.name,
                frame.points.len(),
                classes.len()
            )));
        }
        let pose = *pose;
        let stamp = Timestamp::saturating_from_epoch_secs_f64(frame.stamp);
        let t = stamp.total_nanos();

        // Classified cloud, world frame.
        let data = cloud_data(frame, &pose, classes, rules, confidence);
        self.summary.cloud_points += frame.points.len();
        self.cloud
            .log_with_time(&point_cloud(stamp, data, CLOUD_STRIDE, true), t);

        // Reflections mirrored back (through the planes seen from this pose).
        let local = planes_seen_from(&self.planes, &pose);
        let back = mirror_reflections(frame, classes, &local, self.hull_margin);
        let mut data = Vec::with_capacity(back.len() * MIRRORED_STRIDE as usize);
        for (_, q) in &back {
            push_xyz(&mut data, &(pose * q));
            data.push(Class::Reflection.id());
        }
        self.summary.mirrored_points += back.len();
        self.mirrored
            .log_with_time(&point_cloud(stamp, data, MIRRORED_STRIDE, false), t);

        // Planes (re-sent every frame so seeking always shows them).
        let mut update = self.scene.clone();
        for e in &mut update.entities {
            e.timestamp = Some(stamp);
        }
        self.planes_channel.log_with_time(&update, t);

        // Sensor pose and trajectory.
        self.tf.log_with_time(
            &FrameTransform {
                timestamp: Some(stamp),
                parent_frame_id: WORLD_FRAME.into(),
                child_frame_id: SENSOR_FRAME.into(),
                translation: Some(vector(&pose)),
                rotation: Some(quaternion(&pose)),
            },
            t,
        );
        self.trail.push(to_pose(&pose));
        self.trajectory.log_with_time(
            &PosesInFrame {
                timestamp: Some(stamp),
                frame_id: WORLD_FRAME.into(),
                poses: self.trail.poses(),
            },
            t,
        );
        self.summary.frames += 1;
        Ok(())
    }

    /// Close the recording and move it into place.
    pub fn finish(mut self) -> Result<McapSummary> {
        let writer = self
            .writer
            .take()
            .expect("an unfinished recorder has its writer");
        writer
            .close()
            .map_err(|e| Error::Input(format!("{}: MCAP: {e}", self.tmp.display())))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
        Ok(self.summary)
    }
}

impl Drop for McapRecorder {
    /// An unfinished recording leaves no file behind.
    fn drop(&mut self) {
        if let Some(writer) = self.writer.take() {
            let _ = writer.close();
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// The sensor path shown on `/trajectory`: every pose up to
/// [`Trail::MAX`], then every second, fourth, ... pose, so each message
/// stays bounded on long runs (the recording grew with the square of the
/// frames otherwise).
#[derive(Debug, Default)]
struct Trail {
    kept: Vec<Pose>,
    /// Poses seen; one in `stride` is kept.
    seen: usize,
    stride: usize,
    /// The latest pose, always shown.
    last: Option<Pose>,
}

impl Trail {
    const MAX: usize = 2000;

    fn push(&mut self, pose: Pose) {
        let stride = self.stride.max(1);
        if self.seen.is_multiple_of(stride) {
            self.kept.push(pose);
            if self.kept.len() >= Self::MAX {
                // Keep every second pose and halve the rate from now on.
                let mut i = 0;
                self.kept.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride = stride * 2;
            }
        }
        self.seen += 1;
        self.last = Some(pose);
    }

    /// The poses to show: the kept ones and the latest.
    fn poses(&self) -> Vec<Pose> {
        let mut poses = self.kept.clone();
        if let Some(last) = &self.last {
            if poses.last() != Some(last) {
                poses.push(*last);
            }
        }
        poses
    }
}

/// The `/cloud` records of a frame (`CLOUD_STRIDE` bytes a point, fields
/// as [`point_cloud`] names them): rule 0 and confidence NaN where unknown.
fn cloud_data(
    frame: &Frame,
    pose: &Isometry3<f64>,
    classes: &[Class],
    rules: &[Rule],
    confidence: &[f32],
) -> Vec<u8> {
    let mut data = Vec::with_capacity(frame.points.len() * CLOUD_STRIDE as usize);
    for (i, (pt, class)) in frame.points.iter().zip(classes).enumerate() {
        push_xyz(&mut data, &(pose * pt.position()));
        data.push(class.id());
        data.extend_from_slice(&pt.intensity.to_le_bytes());
        data.push(rules.get(i).map_or(0, |r| r.id()));
        let p = confidence.get(i).copied().unwrap_or(f32::NAN);
        data.extend_from_slice(&p.to_le_bytes());
    }
    data
}

fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

fn push_xyz(buf: &mut Vec<u8>, p: &Point3<f64>) {
    for c in [p.x as f32, p.y as f32, p.z as f32] {
        buf.extend_from_slice(&c.to_le_bytes());
    }
}

fn field(name: &str, offset: u32, t: NumericType) -> PackedElementField {
    PackedElementField {
        name: name.into(),
        offset,
        r#type: t as i32,
    }
}

fn point_cloud(stamp: Timestamp, data: Vec<u8>, stride: u32, intensity: bool) -> PointCloud {
    let mut fields = vec![
        field("x", 0, NumericType::Float32),
        field("y", 4, NumericType::Float32),
        field("z", 8, NumericType::Float32),
        field("class", 12, NumericType::Uint8),
    ];
    if intensity {
        fields.push(field("intensity", 13, NumericType::Float32));
        fields.push(field("rule", 17, NumericType::Uint8));
        fields.push(field("confidence", 18, NumericType::Float32));
    }
    PointCloud {
        timestamp: Some(stamp),
        frame_id: WORLD_FRAME.into(),
        pose: Some(to_pose(&Isometry3::identity())),
        point_stride: stride,
        fields,
        data: bytes::Bytes::from(data),
    }
}

fn vector(pose: &Isometry3<f64>) -> Vector3 {
    let t = pose.translation.vector;
    Vector3 {
        x: t.x,
        y: t.y,
        z: t.z,
    }
}

fn quaternion(pose: &Isometry3<f64>) -> Quaternion {
    let q = pose.rotation;
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

fn to_pose(pose: &Isometry3<f64>) -> Pose {
    Pose {
        position: Some(vector(pose)),
        orientation: Some(quaternion(pose)),
    }
}

fn fg_point(p: &Point3<f64>) -> FgPoint3 {
    FgPoint3 {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// The hull (light) and the panes (stronger) of every plane as translucent
/// triangle fans with outlines, one entity per plane.
fn scene_update(planes: &[BoundedPlane]) -> SceneUpdate {
    let hull_colour = Color {
        r: 0.2,
        g: 0.6,
        b: 1.0,
        a: 0.15,
    };
    let pane_colour = Color {
        r: 0.0,
        g: 0.8,
        b: 0.3,
        a: 0.4,
    };
    let entities = planes
        .iter()
        .enumerate()
        .map(|(i, bp)| {
            let mut polygons = vec![(bp.boundary_3d(), hull_colour)];
            if let Some(panes) = &bp.panes {
                for pane in panes.iter() {
                    let vs = pane.vertices().iter().map(|q| bp.chart.to_3d(q)).collect();
                    polygons.push((vs, pane_colour));
                }
            }
            let mut entity = SceneEntity {
                frame_id: WORLD_FRAME.into(),
                id: format!("plane_{i}"),
                ..Default::default()
            };
            for (vs, colour) in polygons {
                if vs.len() < 3 {
                    continue;
                }
                entity.triangles.push(fan(&vs, colour));
                entity.lines.push(LinePrimitive {
                    r#type: line_primitive::Type::LineLoop as i32,
                    pose: Some(to_pose(&Isometry3::identity())),
                    thickness: 2.0,
                    scale_invariant: true,
                    points: vs.iter().map(fg_point).collect(),
                    color: Some(Color { a: 1.0, ..colour }),
                    ..Default::default()
                });
            }
            entity
        })
        .collect();
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}

/// A triangle fan over a convex polygon as a triangle list.
fn fan(vs: &[Point3<f64>], colour: Color) -> TriangleListPrimitive {
    let points = (1..vs.len() - 1)
        .flat_map(|j| [&vs[0], &vs[j], &vs[j + 1]])
        .map(fg_point)
        .collect();
    TriangleListPrimitive {
        pose: Some(to_pose(&Isometry3::identity())),
        points,
        color: Some(colour),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests;
