//! From the file to the scene: range checks on materials and the sensor,
//! the trajectory, and the surfaces of rooms, boxes, walls, polygons,
//! floors and ceilings with their material names resolved. Every error
//! names the item it comes from (`rooms[0].+x`, `materials.window`).

use std::collections::BTreeMap;
use std::path::Path;

use glam::{DVec2, DVec3};

use super::file::{MaterialFile, SceneFile, SensorFile};
use super::{NamedMaterial, Scene, SensorSetup};
use crate::sensor::SensorModel;
use crate::sim::material::{Material, MaterialKind};
use crate::sim::surface::Surface;
use crate::sim::trajectory::Trajectory;

/// The six sides of a box, in the order they are generated.
const SIDES: [&str; 6] = ["-x", "+x", "-y", "+y", "floor", "ceiling"];

pub(super) type BuildResult<T> = std::result::Result<T, String>;

impl MaterialFile {
    pub(super) fn build(&self) -> BuildResult<Material> {
        let unit = |name: &str, v: f64| -> BuildResult<f64> {
            if (0.0..=1.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("{name} must be in 0..1, got {v}"))
            }
        };
        let peak = |v: f64| -> BuildResult<f64> {
            if (0.0..=100.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("echo_peak must be in 0..100, got {v}"))
            }
        };
        let lobe = |v: f64| -> BuildResult<f64> {
            if (1.0..=1000.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("echo_lobe must be in 1..1000, got {v}"))
            }
        };
        let width = |v: f64| -> BuildResult<f64> {
            if v > 0.0 && v <= 90.0 {
                Ok(v.to_radians())
            } else {
                Err(format!("echo_width_deg must be in (0, 90], got {v}"))
            }
        };
        Ok(match *self {
            MaterialFile::Diffuse { reflectivity } => {
                Material::diffuse(unit("reflectivity", reflectivity)?)
            }
            MaterialFile::Glass {
                reflectance,
                transmittance,
                echo_peak,
                echo_width_deg,
                echo_diffuse,
                echo_lobe,
            } => {
                let r = unit("reflectance", reflectance)?;
                let t = unit("transmittance", transmittance)?;
                if r + t > 1.0 {
                    return Err(format!(
                        "reflectance + transmittance must not exceed 1 (energy), got {r} + {t}"
                    ));
                }
                Material {
                    kind: MaterialKind::Glass,
                    diffuse: unit("echo_diffuse", echo_diffuse)?,
                    lobe: lobe(echo_lobe)?,
                    echo_peak: peak(echo_peak)?,
                    echo_width: width(echo_width_deg)?,
                    reflectance: r,
                    transmittance: t,
                    fresnel: true,
                }
            }
            MaterialFile::Mirror {
                reflectance,
                echo_peak,
                echo_width_deg,
                echo_diffuse,
                echo_lobe,
            } => Material {
                kind: MaterialKind::Mirror,
                diffuse: unit("echo_diffuse", echo_diffuse)?,
                lobe: lobe(echo_lobe)?,
                echo_peak: peak(echo_peak)?,
                echo_width: width(echo_width_deg)?,
                reflectance: unit("reflectance", reflectance)?,
                transmittance: 0.0,
                fresnel: false,
            },
            MaterialFile::OtherReflective {
                reflectivity,
                reflectance,
                echo_peak,
                echo_width_deg,
            } => {
                let rho = unit("reflectivity", reflectivity)?;
                let r = unit("reflectance", reflectance)?;
                if rho + r > 1.0 {
                    return Err(format!(
                        "reflectivity + reflectance must not exceed 1 (energy), got {rho} + {r}"
                    ));
                }
                Material {
                    kind: MaterialKind::OtherReflective,
                    diffuse: rho,
                    lobe: 1.0,
                    echo_peak: peak(echo_peak)?,
                    echo_width: width(echo_width_deg)?,
                    reflectance: r,
                    transmittance: 0.0,
                    fresnel: true,
                }
            }
        })
    }
}

fn finite(what: &str, v: &[f64]) -> BuildResult<()> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what} must be finite numbers"))
    }
}

/// Surfaces are collected with the material names resolved.
struct Builder<'a> {
    names: &'a BTreeMap<String, usize>,
    surfaces: Vec<Surface>,
}

impl Builder<'_> {
    fn material(&self, item: &str, name: &str) -> BuildResult<usize> {
        self.names.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = self.names.keys().map(String::as_str).collect();
            format!(
                "{item}: unknown material '{name}' (defined: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )
        })
    }

    fn push(&mut self, item: &str, vertices: Vec<DVec3>, material: usize) -> BuildResult<()> {
        let s = Surface::new(vertices, material, item.to_string())
            .map_err(|m| format!("{item}: {m}"))?;
        s.triangles().map_err(|m| format!("{item}: {m}"))?;
        self.surfaces.push(s);
        Ok(())
    }

    /// The sides of an oriented box; `inward` for rooms.
    #[allow(clippy::too_many_arguments)]
    fn cuboid(
        &mut self,
        item: &str,
        min: [f64; 3],
        max: [f64; 3],
        yaw_deg: f64,
        default_material: usize,
        per_side: &[Option<usize>; 6],
        omit: &[String],
        sides: &BTreeMap<String, String>,
        inward: bool,
    ) -> BuildResult<()> {
        finite(
            &format!("{item}: min/max/yaw_deg"),
            &[min, max, [yaw_deg; 3]].concat(),
        )?;
        if (0..3).any(|i| !(max[i] > min[i])) {
            return Err(format!(
                "{item}: max must exceed min on every axis, got min {min:?} max {max:?}"
            ));
        }
        for name in omit.iter().chain(sides.keys()) {
            if !SIDES.contains(&name.as_str()) {
                return Err(format!(
                    "{item}: unknown side '{name}' (sides: {})",
                    SIDES.join(", ")
                ));
            }
        }
        let lo = DVec3::from_array(min);
        let hi = DVec3::from_array(max);
        let centre = DVec2::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y));
        let (s, c) = yaw_deg.to_radians().sin_cos();
        let place = |p: DVec3| -> DVec3 {
            let q = DVec2::new(p.x, p.y) - centre;
            DVec3::new(
                centre.x + c * q.x - s * q.y,
                centre.y + s * q.x + c * q.y,
                p.z,
            )
        };
        let corner = |ix: usize, iy: usize, iz: usize| -> DVec3 {
            place(DVec3::new(
                if ix == 0 { lo.x } else { hi.x },
                if iy == 0 { lo.y } else { hi.y },
                if iz == 0 { lo.z } else { hi.z },
            ))
        };
        for (k, side) in SIDES.iter().enumerate() {
            if omit.iter().any(|o| o == side) {
                continue;
            }
            let axis = k / 2;
            let at = k % 2;
            // The four corners with coordinate `axis` fixed, in cyclic order.
            let cyc = [(0, 0), (1, 0), (1, 1), (0, 1)];
            let mut vertices: Vec<DVec3> = cyc
                .iter()
                .map(|&(a, b)| match axis {
                    0 => corner(at, a, b),
                    1 => corner(a, at, b),
                    _ => corner(a, b, at),
                })
                .collect();
            let mut outward = DVec3::ZERO;
            outward[axis] = if at == 0 { -1.0 } else { 1.0 };
            let outward = place(outward) - place(DVec3::ZERO);
            let want = if inward { -outward } else { outward };
            let material = match sides.get(*side) {
                Some(name) => self.material(&format!("{item}.sides.{side}"), name)?,
                None => per_side[k].unwrap_or(default_material),
            };
            let label = format!("{item}.{side}");
            let probe = Surface::new(vertices.clone(), material, label.clone())
                .map_err(|m| format!("{label}: {m}"))?;
            if probe.normal.dot(want) < 0.0 {
                vertices.reverse();
            }
            self.push(&label, vertices, material)?;
        }
        Ok(())
    }
}

impl SceneFile {
    pub(super) fn build(self, origin: &Path) -> BuildResult<Scene> {
        // Materials.
        let mut materials = Vec::new();
        let mut names = BTreeMap::new();
        for (name, spec) in &self.materials {
            let m = spec.build().map_err(|e| format!("materials.{name}: {e}"))?;
            names.insert(name.clone(), materials.len());
            materials.push(NamedMaterial {
                name: name.clone(),
                material: m,
            });
        }

        // Sensor.
        let sensor = self.sensor.build(origin)?;

        // Trajectory.
        let t = &self.trajectory;
        let waypoints: Vec<DVec3> = t.waypoints.iter().map(|w| DVec3::from_array(*w)).collect();
        let trajectory = Trajectory::new(waypoints, t.speed, t.closed, t.heading_smoothing)
            .and_then(|tr| tr.with_tilt_deg(t.tilt_deg.unwrap_or([0.0, 0.0])))
            .and_then(|tr| tr.with_turn_rate_deg(t.turn_rate_deg.unwrap_or(0.0)))
            .map_err(|m| format!("trajectory: {m}"))?;
        let frames = match t.frames {
            Some(0) => return Err("trajectory: frames must be at least 1".into()),
            Some(n) => n,
            None => trajectory.default_frames(sensor.model.rate_hz),
        };

        // Surfaces.
        let mut b = Builder {
            names: &names,
            surfaces: Vec::new(),
        };
        for (i, r) in self.rooms.iter().enumerate() {
            let item = format!("rooms[{i}]");
            let walls = b.material(&item, &r.material)?;
            let floor = r
                .floor
                .as_deref()
                .map(|n| b.material(&format!("{item}.floor"), n))
                .transpose()?;
            let ceiling = r
                .ceiling
                .as_deref()
                .map(|n| b.material(&format!("{item}.ceiling"), n))
                .transpose()?;
            let per_side = [None, None, None, None, floor, ceiling];
            b.cuboid(
                &item, r.min, r.max, r.yaw_deg, walls, &per_side, &r.omit, &r.sides, true,
            )?;
        }
        for (i, x) in self.boxes.iter().enumerate() {
            let item = format!("boxes[{i}]");
            let m = b.material(&item, &x.material)?;
            b.cuboid(
                &item, x.min, x.max, x.yaw_deg, m, &[None; 6], &x.omit, &x.sides, false,
            )?;
        }
        for (i, w) in self.walls.iter().enumerate() {
            let item = format!("walls[{i}]");
            let m = b.material(&item, &w.material)?;
            finite(
                &format!("{item}: from/to/base/height"),
                &[w.from[0], w.from[1], w.to[0], w.to[1], w.base, w.height],
            )?;
            if !(w.height > 0.0) {
                return Err(format!("{item}: height must be positive, got {}", w.height));
            }
            let top = w.base + w.height;
            let v = vec![
                DVec3::new(w.from[0], w.from[1], w.base),
                DVec3::new(w.to[0], w.to[1], w.base),
                DVec3::new(w.to[0], w.to[1], top),
                DVec3::new(w.from[0], w.from[1], top),
            ];
            b.push(&item, v, m)?;
        }
        for (i, p) in self.polygons.iter().enumerate() {
            let item = format!("polygons[{i}]");
            let m = b.material(&item, &p.material)?;
            let v = p.vertices.iter().map(|v| DVec3::from_array(*v)).collect();
            b.push(&item, v, m)?;
        }
        for (list, what, up) in [
            (&self.floors, "floors", true),
            (&self.ceilings, "ceilings", false),
        ] {
            for (i, r) in list.iter().enumerate() {
                let item = format!("{what}[{i}]");
                let m = b.material(&item, &r.material)?;
                finite(
                    &format!("{item}: min/max/z"),
                    &[r.min[0], r.min[1], r.max[0], r.max[1], r.z],
                )?;
                if !(r.max[0] > r.min[0] && r.max[1] > r.min[1]) {
                    return Err(format!("{item}: max must exceed min on x and y"));
                }
                let mut v = vec![
                    DVec3::new(r.min[0], r.min[1], r.z),
                    DVec3::new(r.max[0], r.min[1], r.z),
                    DVec3::new(r.max[0], r.max[1], r.z),
                    DVec3::new(r.min[0], r.max[1], r.z),
                ];
                if !up {
                    v.reverse();
                }
                b.push(&item, v, m)?;
            }
        }
        let surfaces = b.surfaces;
        if surfaces.is_empty() {
            return Err(
                "the scene has no surfaces (rooms, boxes, walls, polygons, floors or ceilings)"
                    .into(),
            );
        }
        if surfaces.len() > u32::MAX as usize / 4 {
            return Err("too many surfaces".into());
        }
        let name = self.name.unwrap_or_else(|| {
            origin
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        });
        Ok(Scene {
            name,
            description: self.description,
            seed: self.seed,
            sensor,
            trajectory,
            frames,
            materials,
            surfaces,
            origin: origin.to_path_buf(),
        })
    }
}

impl SensorFile {
    pub(super) fn build(&self, origin: &Path) -> BuildResult<SensorSetup> {
        let model = if SensorModel::is_builtin(&self.model) {
            SensorModel::resolve(&self.model)
        } else {
            let base = origin.parent().unwrap_or(Path::new("."));
            SensorModel::resolve(&base.join(&self.model).to_string_lossy())
        }
        .map_err(|e| format!("sensor.model: {e}"))?;
        let bad = |m: String| Err(format!("sensor: {m}"));
        if !(self.range_noise >= 0.0 && self.range_noise < 10.0) {
            return bad(format!(
                "range_noise must be in 0..10 m, got {}",
                self.range_noise
            ));
        }
        let max_range = self.max_range.unwrap_or(model.max_range);
        if !(max_range > model.min_range && max_range.is_finite()) {
            return bad(format!(
                "max_range must exceed the sensor's min_range ({} m), got {max_range}",
                model.min_range
            ));
        }
        let max_range = max_range.min(model.max_range);
        if let Some(c) = self.crop_range {
            if !(c > model.min_range && c.is_finite()) {
                return bad(format!(
                    "crop_range must exceed the sensor's min_range ({} m), got {c}",
                    model.min_range
                ));
            }
        }
        if self.max_bounces > 8 {
            return bad(format!(
                "max_bounces must be at most 8, got {}",
                self.max_bounces
            ));
        }
        if !(self.intensity_gain > 0.0 && self.intensity_gain.is_finite()) {
            return bad(format!(
                "intensity_gain must be positive, got {}",
                self.intensity_gain
            ));
        }
        if !(self.detection_threshold > 0.0 && self.detection_threshold <= 255.0) {
            return bad(format!(
                "detection_threshold must be in (0, 255], got {}",
                self.detection_threshold
            ));
        }
        if let Some(b) = self.blind_sector_deg {
            if !b.iter().all(|x| x.is_finite()) {
                return bad("blind_sector_deg must be two finite angles".into());
            }
        }
        let dropout = self.dropout.unwrap_or(0.0);
        if !(0.0..=0.5).contains(&dropout) {
            return bad(format!("dropout must be in 0..0.5, got {dropout}"));
        }
        Ok(SensorSetup {
            sweep: self.sweep.unwrap_or(false),
            dropout,
            blind_sector_deg: self.blind_sector_deg,
            model,
            range_noise: self.range_noise,
            max_range,
            crop_range: self.crop_range,
            max_bounces: self.max_bounces,
            intensity_gain: self.intensity_gain,
            detection_threshold: self.detection_threshold,
        })
    }
}
