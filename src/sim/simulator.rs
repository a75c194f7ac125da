//! One frame at a time: cast every beam of the sensor pattern from the pose
//! of frame `k`, turn its echoes into returns, add range noise and write the
//! points in the sensor frame.
//!
//! A spinning sensor casts the same beams every frame (its rings ×
//! columns); a rosette sensor ([`Rosette`]) casts the pulses of its
//! pattern over the frame's period, which differ from frame to frame, and
//! writes each point's grid row as its ring. Each sensor's returns follow
//! its return mode ([`returns::select`], [`returns::select_triple`]) and its
//! intensities its scale (`simulated_intensity`).
//!
//! With the sensor's `sweep` on ([`SensorSetup::sweep`](super::scene::SensorSetup::sweep)),
//! a frame is not taken at one instant: its beams are fired over the
//! sensor's period (`1 / rate_hz` of its model) while the sensor moves
//! along the trajectory, each cast from the pose at its own firing time,
//! and each point is written in the sensor frame *of that time*, as a real
//! driver writes it, with [`Point::time`] its firing time after the
//! frame's stamp. The convention: **a frame's stamp and its pose (the pose
//! file) are the sweep's start**, the first firing (as Ouster's `t` counts
//! from the scan's start), so times lie in `[0, period)`. A spinning
//! sensor's column `c` (azimuth `c · 360 / columns - 180` deg) fires at
//! `c / (columns · rate_hz)`: the head turns counter-clockwise from the
//! seam behind it (the same column order as [`SensorModel::column_of`](crate::sensor::SensorModel::column_of)); a
//! rosette's pulse `i` fires at `i / pulses_per_second`. With `sweep` off
//! every point has time 0 and the output is what it always was.
//!
//! Frames are independent: frame `k` depends only on the scene, `k` and the
//! run's seed (through [`frame_seed`]), so they can be generated in any
//! order or in parallel and the output is identical.

use glam::{DMat3, DVec3};

use super::echo::{BeamTracer, Echo};
use super::labels::{raycast_label, LabelRule};
use super::material::MaterialKind;
use super::raycast::Hit;
use super::returns;
use super::scene::Scene;
use crate::cloud::{Frame, IntensityScale, Point};
use crate::io::StampedPose;
use crate::rng::SplitMix64;
use crate::sensor::{ReturnMode, Rosette};

/// A simulated reflectivity reads this for a white Lambertian target at
/// normal incidence: the top of a reflectivity byte's diffuse range (Livox:
/// 0-150 diffuse, 151-255 retroreflective).
const DIFFUSE_FULL_SCALE: f64 = 150.0;

/// Timestamp of frame 0, seconds (frame `k` is at `EPOCH + k / rate`).
pub const EPOCH_SECONDS: u64 = 1_700_000_000;

/// Ground truth of one point beyond its label: which surfaces made it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PointTruth {
    /// Surface that scattered the echo back.
    pub surface: u32,
    /// First surface that reflected the path (reflections), else the first
    /// glass it crossed (obstacles behind glass), else
    /// [`super::echo::NO_SURFACE`].
    pub via: u32,
    /// Specular reflections on the path.
    pub bounces: u8,
    /// The label of the echo's physical path (see
    /// [`LabelRule::Physical`]); the point's `label` follows the
    /// simulator's [`LabelRule`].
    pub physical: u8,
}

/// A simulated frame with its true pose and per-point truth.
#[derive(Debug, Clone)]
pub struct SimFrame {
    /// The points (sensor frame), labelled.
    pub frame: Frame,
    /// True `T_world_sensor`.
    pub pose: StampedPose,
    /// Per-point truth, parallel to `frame.points`.
    pub truth: Vec<PointTruth>,
}

/// The seed of frame `k`'s noise generator, from the run's seed.
pub fn frame_seed(seed: u64, k: usize) -> u64 {
    let mut g = SplitMix64::new(seed);
    let base = g.next_u64();
    SplitMix64::new(base ^ (k as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)).next_u64()
}

/// The simulator of one scene: the ray-casting index and the beam pattern,
/// built once and shared by all frames (and threads).
#[derive(Debug)]
pub struct Simulator {
    scene: Scene,
    tracer: BeamTracer,
    /// Unit beam directions in the sensor frame, column-major (all rings
    /// of a column in turn), without the columns of the blind sector (empty
    /// for a rosette sensor).
    beams: Vec<DVec3>,
    /// Firing time of each of `beams` after the frame's stamp, seconds
    /// (its column's share of the period; used only with `sweep`).
    beam_times: Vec<f64>,
    /// The rosette of a rosette sensor, and its pulses per frame.
    rosette: Option<(Rosette, usize)>,
    min_signal: f64,
    period_us: u64,
    /// Material class of every surface (for the ray-cast labels).
    kinds: Vec<MaterialKind>,
    labels: LabelRule,
}

impl Simulator {
    /// Prepare a scene for simulation.
    pub fn new(scene: &Scene) -> Self {
        let sensor = &scene.sensor;
        let model = &sensor.model;
        let materials: Vec<_> = scene.materials.iter().map(|m| m.material).collect();
        let min_signal = sensor.detection_threshold / sensor.intensity_gain;
        let tracer = BeamTracer::new(
            &scene.surfaces,
            &materials,
            sensor.max_range,
            sensor.max_bounces,
            min_signal,
        );
        let rings = model.rings();
        let rosette = model
            .rosette
            .clone()
            .map(|r| {
                let pulses = (r.pulses_per_second / model.rate_hz).round() as usize;
                (r, pulses)
            })
            .filter(|_| model.is_rosette());
        let spinning = if rosette.is_some() { 0 } else { model.columns };
        let mut beams = Vec::with_capacity(rings * spinning);
        let mut beam_times = Vec::with_capacity(rings * spinning);
        for col in 0..spinning {
            if sensor.is_blind(model.column_azimuth_deg(col)) {
                continue;
            }
            let time = col as f64 / (spinning as f64 * model.rate_hz);
            for ring in 0..rings {
                let d = model.beam_direction(ring, col);
                beams.push(DVec3::new(d.x, d.y, d.z));
                beam_times.push(time);
            }
        }
        let period_us = (1e6 / model.rate_hz).round().max(1.0) as u64;
        let kinds = scene
            .surfaces
            .iter()
            .map(|s| scene.material_of(s).kind)
            .collect();
        Self {
            scene: scene.clone(),
            tracer,
            beams,
            beam_times,
            rosette,
            min_signal,
            period_us,
            kinds,
            labels: LabelRule::default(),
        }
    }

    /// The same simulator labelling its points by `rule` (default: 3DRef's
    /// ray-cast rule).
    pub fn with_label_rule(mut self, rule: LabelRule) -> Self {
        self.labels = rule;
        self
    }

    /// The rule the points' labels follow.
    pub fn label_rule(&self) -> LabelRule {
        self.labels
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Beams cast per frame (the pattern without the blind sector; a
    /// rosette's pulses per frame).
    pub fn beam_count(&self) -> usize {
        match &self.rosette {
            Some((_, pulses)) => *pulses,
            None => self.beams.len(),
        }
    }

    /// Sensor-frame direction and ring (grid row) of pulse `i` of a
    /// rosette sensor's frame `k`; `None` in the blind sector.
    #[inline]
    fn rosette_pulse(&self, rosette: &Rosette, k: usize, i: usize) -> Option<(DVec3, u16)> {
        let t = (k as f64 * self.period_us as f64 * 1e-6) + i as f64 / rosette.pulses_per_second;
        let (az, el) = rosette.angles_deg(t);
        if self.scene.sensor.is_blind(az) {
            return None;
        }
        let d = crate::sensor::rosette::direction(az, el);
        let model = &self.scene.sensor.model;
        let ring = model.ring_of(&nalgebra::Point3::new(d[0], d[1], d[2]))?;
        Some((DVec3::new(d[0], d[1], d[2]), ring as u16))
    }

    /// The beam tracer (for inspecting single beams).
    pub fn tracer(&self) -> &BeamTracer {
        &self.tracer
    }

    /// Name (`{:.6}` seconds) and timestamp of frame `k`.
    pub fn stamp(&self, k: usize) -> (String, f64) {
        let us = EPOCH_SECONDS * 1_000_000 + k as u64 * self.period_us;
        let name = format!("{}.{:06}", us / 1_000_000, us % 1_000_000);
        let stamp = us as f64 * 1e-6;
        (name, stamp)
    }

    /// True pose of frame `k`: at its stamp, the start of its sweep.
    pub fn pose(&self, k: usize) -> StampedPose {
        let t = k as f64 * self.period_us as f64 * 1e-6;
        StampedPose {
            stamp: self.stamp(k).1,
            pose: self.scene.trajectory.pose(t),
        }
    }

    /// The sensor's rotation and origin in the world `time` seconds after
    /// frame `k`'s stamp.
    fn pose_at(&self, k: usize, time: f64) -> (DMat3, DVec3) {
        let t = k as f64 * self.period_us as f64 * 1e-6 + time;
        to_glam(&self.scene.trajectory.pose(t))
    }

    /// Firing time of beam `i` of frame `k` after the frame's stamp,
    /// seconds: 0 unless the sensor sweeps.
    #[inline]
    fn firing_time(&self, i: usize) -> f64 {
        if !self.scene.sensor.sweep {
            return 0.0;
        }
        match &self.rosette {
            Some((r, _)) => i as f64 / r.pulses_per_second,
            None => self.beam_times[i],
        }
    }

    /// The detected echoes of one beam (world-frame `origin` and unit `dir`),
    /// merged and sorted by range, before return selection and noise.
    pub fn beam_echoes(&self, origin: DVec3, dir: DVec3) -> Vec<Echo> {
        let mut echoes = Vec::new();
        self.echoes_into(origin, dir, &mut echoes);
        echoes
    }

    /// The echoes of one beam into `echoes`; returns the first surface the
    /// straight beam meets.
    #[inline]
    fn echoes_into(&self, origin: DVec3, dir: DVec3, echoes: &mut Vec<Echo>) -> Option<Hit> {
        let model = &self.scene.sensor.model;
        echoes.clear();
        let first = self.tracer.trace(origin, dir, echoes);
        returns::merge(echoes, model.range_resolution);
        returns::detect(
            echoes,
            self.min_signal,
            model.min_range,
            self.scene.sensor.max_range,
        );
        first
    }

    /// Simulate frame `k` with the run's `seed`.
    pub fn frame(&self, k: usize, seed: u64) -> SimFrame {
        let sensor = &self.scene.sensor;
        let model = &sensor.model;
        let pose = self.pose(k);
        let (name, stamp) = self.stamp(k);
        let (mut rot, mut origin) = to_glam(&pose.pose);
        // The firing time the pose `(rot, origin)` is for.
        let mut posed_at = 0.0;
        let mut rng = SplitMix64::new(frame_seed(seed, k));
        let crop = sensor.crop_range.unwrap_or(f64::INFINITY);
        let res = model.range_resolution;
        let rings = model.rings();
        let beams = self.beam_count();
        let mut points = Vec::with_capacity(beams + beams / 16);
        let mut truth = Vec::with_capacity(points.capacity());
        let mut echoes = Vec::with_capacity(8);
        let reflectivity = model.simulated_intensity == IntensityScale::Reflectivity;
        for i in 0..beams {
            let (dir_s, ring) = match &self.rosette {
                Some((r, _)) => match self.rosette_pulse(r, k, i) {
                    Some(pulse) => pulse,
                    None => continue,
                },
                None => (self.beams[i], (i % rings) as u16),
            };
            if sensor.dropout > 0.0 && rng.unit() < sensor.dropout {
                continue;
            }
            let time = self.firing_time(i);
            if time != posed_at {
                (rot, origin) = self.pose_at(k, time);
                posed_at = time;
            }
            let dir_w = rot * dir_s;
            let first_hit = self.echoes_into(origin, dir_w, &mut echoes);
            let (first, second) = returns::select(&echoes, model.return_mode);
            let Some(first) = first else { continue };
            let r1 = noisy(first.range, sensor.range_noise, &mut rng);
            let second = second.map(|e| (e, noisy(e.range, sensor.range_noise, &mut rng)));
            if r1 > crop {
                continue;
            }
            let label_of = |e: &Echo, r: f64| match self.labels {
                LabelRule::Physical => e.label,
                LabelRule::Raycast3dref => raycast_label(
                    first_hit,
                    r,
                    origin + dir_w * r,
                    &self.kinds,
                    self.tracer.index(),
                ),
            };
            let mut emit = |e: &Echo, r: f64, ret: u8| {
                let p = dir_s * r;
                let intensity = if reflectivity {
                    // σ·A: the signal with the range's 1/r² undone.
                    e.signal * e.range * e.range * DIFFUSE_FULL_SCALE
                } else {
                    e.signal * sensor.intensity_gain
                };
                points.push(Point {
                    xyz: [p.x as f32, p.y as f32, p.z as f32],
                    intensity: intensity.min(255.0).round() as f32,
                    ring,
                    ret,
                    label: label_of(e, r),
                    time: time as f32,
                });
                truth.push(PointTruth {
                    surface: e.surface,
                    via: e.via,
                    bounces: e.bounces,
                    physical: e.label,
                });
            };
            emit(&first, r1, 1);
            if let Some((e, r2)) = second {
                // As 3DRef: return 2 only where it differs from return 1.
                if r2 <= crop && (r2 - r1).abs() > res {
                    emit(&e, r2, 2);
                }
            }
            if model.return_mode == ReturnMode::Triple {
                // The third of three returns, where it differs from both.
                if let Some(e) = returns::select_triple(&echoes)[2] {
                    let r3 = noisy(e.range, sensor.range_noise, &mut rng);
                    let r2 = second.map_or(r1, |(_, r2)| r2);
                    if r3 <= crop && (r3 - r1).abs() > res && (r3 - r2).abs() > res {
                        emit(&e, r3, 3);
                    }
                }
            }
        }
        SimFrame {
            frame: Frame {
                name,
                stamp,
                points,
                has_labels: true,
                dropped_non_finite: 0,
                // The echo's signal, or the sensor's reflectivity.
                intensity_scale: Some(model.simulated_intensity),
            },
            pose,
            truth,
        }
    }
}

/// The rotation matrix and the translation of a pose, as glam types.
fn to_glam(pose: &nalgebra::Isometry3<f64>) -> (DMat3, DVec3) {
    let q = pose.rotation.to_rotation_matrix();
    let m = q.matrix();
    let rot = DMat3::from_cols(
        DVec3::new(m[(0, 0)], m[(1, 0)], m[(2, 0)]),
        DVec3::new(m[(0, 1)], m[(1, 1)], m[(2, 1)]),
        DVec3::new(m[(0, 2)], m[(1, 2)], m[(2, 2)]),
    );
    let tr = pose.translation.vector;
    (rot, DVec3::new(tr.x, tr.y, tr.z))
}

/// `range + sigma · N(0, 1)`, never negative; no random draw when `sigma`
/// is zero.
#[inline]
fn noisy(range: f64, sigma: f64, rng: &mut SplitMix64) -> f64 {
    if sigma > 0.0 {
        (range + sigma * rng.normal()).max(0.0)
    } else {
        range
    }
}
