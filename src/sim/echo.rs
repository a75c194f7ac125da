//! Beam physics: follow one laser beam through the scene and collect its
//! echoes.
//!
//! A beam travels until it hits a surface. There it produces
//!
//! - a **surface echo** of strength `σ(θ)` (see [`super::material`]);
//! - at glass, a **transmitted** ray that continues straight on, with power
//!   factor `T(θ)`;
//! - at glass, mirrors and other reflective surfaces, a **specular** ray in
//!   the mirrored direction, with power factor `R(θ)`.
//!
//! Light scattered back by a later surface returns along the same path
//! (reciprocity), so every factor applies twice: the path attenuation is
//! `A = Π T² R²`. An echo reached after a total one-way path length `r` has
//! signal `σ(θ) · A / r²`; the sensor reports it at range `r` along its
//! original beam direction, which is why reflections appear behind mirrors.
//!
//! Each echo carries the 3DRef label of its path: 1 normal (diffuse, direct),
//! 2/3/4 the surface echo of glass / mirror / other reflective, 5 anything
//! reached after a specular reflection, 6 a diffuse surface reached through
//! glass without reflection.

use glam::DVec3;

use super::material::Material;
use super::raycast::{Hit, SceneIndex};
use super::surface::Surface;

/// Interactions (hits) followed per beam at most, whatever their kind.
const MAX_INTERACTIONS: u32 = 8;
/// Echoes weaker than this fraction of the detection limit are not kept
/// (they could not change a detectable echo when merged).
const KEEP_FRACTION: f64 = 1e-3;

/// 3DRef label ids.
pub mod label {
    /// No label (3DRef's 0: the ray-cast rule could not place the point).
    pub const UNLABELED: u8 = 0;
    /// Diffuse surface reached directly.
    pub const NORMAL: u8 = 1;
    /// Surface echo of glass.
    pub const GLASS: u8 = 2;
    /// Surface echo of a mirror.
    pub const MIRROR: u8 = 3;
    /// Surface echo of another reflective surface.
    pub const OTHER_REFLECTIVE: u8 = 4;
    /// Anything reached after a specular reflection.
    pub const REFLECTION: u8 = 5;
    /// Diffuse surface reached through glass, without reflection.
    pub const OBSTACLE_BEHIND_GLASS: u8 = 6;
}

/// One echo along a beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Echo {
    /// Total one-way path length, metres: the range the sensor reports.
    pub range: f64,
    /// Received signal `σ · A / r²` (intensity before the sensor gain).
    pub signal: f64,
    /// 3DRef label of the echo's path.
    pub label: u8,
    /// Surface that scattered the echo.
    pub surface: u32,
    /// The surface the path went "through" on its way: the first surface
    /// that reflected it (reflections) or else the first glass it crossed
    /// (obstacles behind glass); [`NO_SURFACE`] for a direct echo.
    pub via: u32,
    /// Specular reflections on the path (0 for a direct or transmitted
    /// echo).
    pub bounces: u8,
}

/// Marker for "no surface" in [`Echo::via`].
pub const NO_SURFACE: u32 = u32::MAX;

/// The state of a ray: how far it has come and what happened on the way.
#[derive(Debug, Clone, Copy)]
struct PathState {
    length: f64,
    power: f64,
    reflected: bool,
    transmitted: bool,
    bounces: u32,
    interactions: u32,
    skip: Option<u32>,
    reflector: u32,
    transmitter: u32,
}

/// Per-surface data the tracer needs at a hit.
#[derive(Debug, Clone, Copy)]
struct SurfaceOptics {
    normal: DVec3,
    material: Material,
}

/// Follows beams through a scene (immutable, shared between threads).
#[derive(Debug)]
pub struct BeamTracer {
    index: SceneIndex,
    surfaces: Vec<SurfaceOptics>,
    max_range: f64,
    min_signal: f64,
    max_bounces: u32,
    max_echo: f64,
}

impl BeamTracer {
    /// A tracer over `surfaces` with their `materials`. Beams are followed
    /// for `max_range` metres of path and `max_bounces` specular
    /// reflections; `min_signal` is the weakest detectable signal (rays that
    /// can no longer produce one are dropped).
    pub fn new(
        surfaces: &[Surface],
        materials: &[Material],
        max_range: f64,
        max_bounces: u32,
        min_signal: f64,
    ) -> Self {
        let optics: Vec<SurfaceOptics> = surfaces
            .iter()
            .map(|s| SurfaceOptics {
                normal: s.normal,
                material: materials[s.material],
            })
            .collect();
        let max_echo = optics
            .iter()
            .map(|o| o.material.max_echo())
            .fold(0.0, f64::max);
        Self {
            index: SceneIndex::new(surfaces),
            surfaces: optics,
            max_range,
            min_signal,
            max_bounces,
            max_echo,
        }
    }

    /// The ray-casting index.
    pub fn index(&self) -> &SceneIndex {
        &self.index
    }

    /// All echoes of the beam `origin + t·dir` (unit `dir`), appended to
    /// `out` in the order they were found (not sorted). Returns the first
    /// surface the straight beam meets (what 3DRef's ray-cast labelling
    /// looks at, [`super::labels`]), `None` when it meets nothing.
    pub fn trace(&self, origin: DVec3, dir: DVec3, out: &mut Vec<Echo>) -> Option<Hit> {
        let hit = self.index.cast(origin, dir, self.max_range, None)?;
        let start = PathState {
            length: 0.0,
            power: 1.0,
            reflected: false,
            transmitted: false,
            bounces: 0,
            interactions: 0,
            skip: None,
            reflector: NO_SURFACE,
            transmitter: NO_SURFACE,
        };
        self.interact(origin, dir, start, hit, out);
        Some(hit)
    }

    fn follow(&self, origin: DVec3, dir: DVec3, path: PathState, out: &mut Vec<Echo>) {
        let reach = self.max_range - path.length;
        if reach <= 0.0 {
            return;
        }
        if let Some(hit) = self.index.cast(origin, dir, reach, path.skip) {
            self.interact(origin, dir, path, hit, out);
        }
    }

    /// The echo of the surface `hit` and the rays leaving it.
    fn interact(&self, origin: DVec3, dir: DVec3, path: PathState, hit: Hit, out: &mut Vec<Echo>) {
        let surf = &self.surfaces[hit.surface as usize];
        let m = &surf.material;
        let r = path.length + hit.t;
        let r2 = r * r;
        let n_dot = surf.normal.dot(dir);
        let cos = n_dot.abs().min(1.0);

        // Surface echo.
        let sigma = m.surface_echo(cos);
        let signal = sigma * path.power / r2;
        if signal >= KEEP_FRACTION * self.min_signal {
            let label = if path.reflected {
                label::REFLECTION
            } else if m.kind.is_reflective() {
                m.kind.label()
            } else if path.transmitted {
                label::OBSTACLE_BEHIND_GLASS
            } else {
                label::NORMAL
            };
            out.push(Echo {
                range: r,
                signal,
                label,
                surface: hit.surface,
                via: if path.reflector != NO_SURFACE {
                    path.reflector
                } else {
                    path.transmitter
                },
                bounces: path.bounces as u8,
            });
        }
        if path.interactions + 1 >= MAX_INTERACTIONS {
            return;
        }
        let point = origin + dir * hit.t;
        // The best signal any later echo could have: the path only grows.
        let can_detect = |power: f64| power * self.max_echo / r2 >= self.min_signal;

        // Specular ray.
        if m.reflectance > 0.0 && path.bounces < self.max_bounces {
            let rr = m.reflectance(cos);
            let power = path.power * rr * rr;
            if can_detect(power) {
                let mirrored = dir - surf.normal * (2.0 * n_dot);
                let next = PathState {
                    length: r,
                    power,
                    reflected: true,
                    bounces: path.bounces + 1,
                    interactions: path.interactions + 1,
                    skip: Some(hit.surface),
                    reflector: if path.reflector == NO_SURFACE {
                        hit.surface
                    } else {
                        path.reflector
                    },
                    ..path
                };
                self.follow(point, mirrored.normalize(), next, out);
            }
        }
        // Transmitted ray.
        if m.transmittance > 0.0 {
            let tt = m.transmittance(cos);
            let power = path.power * tt * tt;
            if can_detect(power) {
                let next = PathState {
                    length: r,
                    power,
                    transmitted: true,
                    interactions: path.interactions + 1,
                    skip: Some(hit.surface),
                    transmitter: if path.transmitter == NO_SURFACE {
                        hit.surface
                    } else {
                        path.transmitter
                    },
                    ..path
                };
                self.follow(point, dir, next, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::material::MaterialKind;
    use super::*;

    fn wall_at_x(x: f64, material: usize) -> Surface {
        Surface::new(
            vec![
                DVec3::new(x, -10.0, -10.0),
                DVec3::new(x, 10.0, -10.0),
                DVec3::new(x, 10.0, 10.0),
                DVec3::new(x, -10.0, 10.0),
            ],
            material,
            format!("x={x}"),
        )
        .unwrap()
    }

    fn glass() -> Material {
        Material {
            kind: MaterialKind::Glass,
            diffuse: 0.02,
            lobe: 1.0,
            echo_peak: 1.0,
            echo_width: 3f64.to_radians(),
            reflectance: 0.1,
            transmittance: 0.8,
            fresnel: true,
        }
    }

    #[test]
    fn glass_gives_surface_transmitted_and_reflected_echoes() {
        // Sensor at x=0 between a wall at x=-3 and glass at x=+2, with a wall
        // behind the glass at x=+6.
        let surfaces = [wall_at_x(2.0, 1), wall_at_x(6.0, 0), wall_at_x(-3.0, 0)];
        let tracer = BeamTracer::new(&surfaces, &[Material::diffuse(0.8), glass()], 60.0, 2, 1e-6);
        let mut echoes = Vec::new();
        tracer.trace(DVec3::ZERO, DVec3::X, &mut echoes);
        echoes.sort_by(|a, b| a.range.total_cmp(&b.range));
        let got: Vec<(u8, f64)> = echoes
            .iter()
            .map(|e| (e.label, (e.range * 1e9).round() / 1e9))
            .collect();
        // Glass at 2 m, reflection of the back wall at 2 + 5 = 7 m, obstacle
        // behind glass at 6 m.
        assert!(got.contains(&(label::GLASS, 2.0)), "{got:?}");
        assert!(
            got.contains(&(label::OBSTACLE_BEHIND_GLASS, 6.0)),
            "{got:?}"
        );
        assert!(got.contains(&(label::REFLECTION, 7.0)), "{got:?}");
        // Both walls are diffuse and end their rays: exactly three echoes.
        assert_eq!(echoes.len(), 3, "{got:?}");
    }

    #[test]
    fn bounces_are_limited() {
        // Two parallel mirrors facing each other: the beam ping-pongs.
        let mirror = Material {
            kind: MaterialKind::Mirror,
            diffuse: 0.01,
            lobe: 1.0,
            echo_peak: 0.0,
            echo_width: 1.0,
            reflectance: 0.95,
            transmittance: 0.0,
            fresnel: false,
        };
        let surfaces = [wall_at_x(1.0, 0), wall_at_x(-1.0, 0)];
        for bounces in 0..4 {
            let tracer = BeamTracer::new(&surfaces, &[mirror], 60.0, bounces, 1e-9);
            let mut echoes = Vec::new();
            tracer.trace(DVec3::ZERO, DVec3::X, &mut echoes);
            assert_eq!(echoes.len() as u32, bounces + 1);
            let last = echoes.last().unwrap();
            assert!((last.range - (1.0 + 2.0 * bounces as f64)).abs() < 1e-9);
        }
    }
}
