//! A scene being drawn: the scene-file tables a family fills in, the
//! random draws within physical ranges, and the building blocks every
//! family shares (glazing with mullions, furniture, people, the street
//! outside, walks and loops).
//!
//! Every draw goes through one generator seeded from the family and seed,
//! so a scene is a function of (family, seed). Solids are placed through
//! [`Draft::solid`], which refuses one that overlaps another or comes
//! within [`PATH_CLEARANCE`] of the sensor's path: the trajectory is drawn
//! before the clutter.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};

use crate::rng::SplitMix64;
use crate::sim::scene::file::{
    BoxFile, MaterialFile, PolygonFile, RectFile, SceneFile, SensorFile, TrajectoryFile, WallFile,
};

/// Closest a solid placed by [`Draft::solid`] may come to the sensor's
/// path (horizontal distance), metres: room to walk past.
pub const PATH_CLEARANCE: f64 = 0.6;
/// A reflective panel is hung this far in front of the wall that carries
/// it, metres (so that the two never share a plane).
pub const PANEL_OFFSET: f64 = 0.02;
/// How far apart the way out and the way back of a walk are, metres.
const TURN_WIDTH: f64 = 0.5;
/// The 3DRef crop range every family keeps, metres.
const CROP_RANGE: f64 = 25.0;

/// Which kind of glass a family's glazing is, when a family (or the mixed
/// family) does not leave it to chance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GlassStyle {
    /// Ordinary float glass: low reflectance, high transmittance.
    Clear,
    /// Solar-control coating or tint: reflectance close to transmittance.
    Coated,
}

/// How a glazed wall is built: panes of `glass` between vertical mullions
/// of `frame`, a sill below the panes and a head above them. Heights are
/// above the floor the wall stands on.
#[derive(Debug, Clone, Copy)]
pub struct Glazing<'a> {
    /// Top of the sill (opaque below), metres.
    pub sill: f64,
    /// Top of the panes (opaque above, up to `top`), metres.
    pub head: f64,
    /// The wall's full height, metres.
    pub top: f64,
    /// Pane width aimed at (the wall is split into whole panes), metres.
    pub pane: f64,
    /// Mullion width, metres.
    pub mullion: f64,
    /// Material of the panes.
    pub glass: &'a str,
    /// Material of sill, head and mullions.
    pub frame: &'a str,
}

/// An axis-aligned footprint of a solid, with its height range.
#[derive(Debug, Clone, Copy)]
struct Solid {
    min: DVec3,
    max: DVec3,
}

/// A scene in the making (see the module doc).
pub struct Draft {
    rng: SplitMix64,
    /// The tables being filled in.
    pub(crate) file: SceneFile,
    solids: Vec<Solid>,
    /// The sensor's path (horizontal), once drawn.
    path: Vec<DVec2>,
    /// Glass style forced on every glazing (the mixed family).
    pub style: Option<GlassStyle>,
    names: BTreeMap<String, usize>,
}

impl Draft {
    /// An empty draft drawing from `seed`; the sensor is the QT64 with a
    /// random noise level, dropout and, half of the time, the operator's
    /// blind sector.
    pub fn new(name: &str, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let blind = rng.unit() < 0.5;
        let sensor = SensorFile {
            model: "pandar_qt64".into(),
            range_noise: 0.005 + 0.025 * rng.unit(),
            max_range: None,
            crop_range: Some(CROP_RANGE),
            max_bounces: 2,
            intensity_gain: 20_000.0,
            detection_threshold: 3.0,
            blind_sector_deg: blind.then_some([157.5, 202.5]),
            dropout: Some(0.03 * rng.unit()),
            sweep: None,
        };
        let noise_seed = rng.next_u64() >> 12;
        Self {
            rng,
            file: SceneFile {
                name: Some(name.into()),
                description: String::new(),
                seed: noise_seed,
                sensor,
                trajectory: TrajectoryFile {
                    waypoints: Vec::new(),
                    speed: 1.0,
                    closed: false,
                    heading_smoothing: 1.0,
                    frames: None,
                    tilt_deg: None,
                    turn_rate_deg: None,
                },
                materials: BTreeMap::new(),
                rooms: Vec::new(),
                boxes: Vec::new(),
                walls: Vec::new(),
                polygons: Vec::new(),
                floors: Vec::new(),
                ceilings: Vec::new(),
            },
            solids: Vec::new(),
            path: Vec::new(),
            style: None,
            names: BTreeMap::new(),
        }
    }

    // ------------------------------------------------------------ draws

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.rng.unit()
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.rng.unit() < p
    }

    /// Uniform integer in `lo..=hi`.
    pub fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.rng.below(hi - lo + 1)
    }

    /// One of `items`, uniformly.
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.rng.below(items.len())]
    }

    // -------------------------------------------------------- materials

    fn material(&mut self, base: &str, m: MaterialFile) -> String {
        let n = self.names.entry(base.to_string()).or_insert(0);
        *n += 1;
        let name = format!("{base}-{n}");
        self.file.materials.insert(name.clone(), m);
        name
    }

    /// A diffuse material with a reflectivity in `[lo, hi)`.
    pub fn diffuse(&mut self, base: &str, lo: f64, hi: f64) -> String {
        let reflectivity = round3(self.uniform(lo, hi));
        self.material(base, MaterialFile::Diffuse { reflectivity })
    }

    /// A glass material of `style` (or the draft's forced style).
    pub fn glass(&mut self, style: GlassStyle) -> String {
        let style = self.style.unwrap_or(style);
        let (reflectance, transmittance) = match style {
            // Float glass: about 4 % per face, a little more with dirt or
            // a low-e layer; most of the rest goes through.
            GlassStyle::Clear => {
                let r = self.uniform(0.04, 0.15);
                (r, self.uniform(0.70, (0.95 - r).min(0.92)))
            }
            // Solar-control and tinted glass: R and T of one size.
            GlassStyle::Coated => {
                let r = self.uniform(0.22, 0.45);
                let t = (r * self.uniform(0.7, 1.3)).min(0.95 - r);
                (r, t)
            }
        };
        let m = MaterialFile::Glass {
            reflectance: round3(reflectance),
            transmittance: round3(transmittance),
            echo_peak: round3(self.uniform(0.5, 2.0)),
            echo_width_deg: round3(self.uniform(2.0, 5.0)),
            echo_diffuse: round3(self.uniform(0.01, 0.05)),
            echo_lobe: round3(self.uniform(4.0, 12.0)),
        };
        let base = match style {
            GlassStyle::Clear => "glass",
            GlassStyle::Coated => "coated-glass",
        };
        self.material(base, m)
    }

    /// A silvered mirror.
    pub fn mirror(&mut self) -> String {
        let m = MaterialFile::Mirror {
            reflectance: round3(self.uniform(0.8, 0.97)),
            echo_peak: round3(self.uniform(0.2, 1.0)),
            echo_width_deg: round3(self.uniform(1.0, 3.0)),
            echo_diffuse: round3(self.uniform(0.005, 0.03)),
            echo_lobe: 1.0,
        };
        self.material("mirror", m)
    }

    // ---------------------------------------------------------- surfaces

    /// A vertical wall from `a` to `b` (floor-plan points), `base` to
    /// `base + height`.
    pub fn wall(&mut self, a: DVec2, b: DVec2, base: f64, height: f64, material: &str) {
        if a.distance(b) < 1e-3 || height <= 1e-3 {
            return;
        }
        self.file.walls.push(WallFile {
            from: [a.x, a.y],
            to: [b.x, b.y],
            base,
            height,
            material: material.into(),
        });
    }

    /// A horizontal polygon at height `z` (floor-plan vertices).
    pub fn slab(&mut self, outline: &[DVec2], z: f64, material: &str) {
        self.file.polygons.push(PolygonFile {
            vertices: outline.iter().map(|p| [p.x, p.y, z]).collect(),
            material: material.into(),
        });
    }

    /// A horizontal rectangle at height `z`.
    pub fn floor_rect(&mut self, min: DVec2, max: DVec2, z: f64, material: &str) {
        self.file.floors.push(RectFile {
            min: min.to_array(),
            max: max.to_array(),
            z,
            material: material.into(),
        });
    }

    /// A ceiling rectangle at height `z` (facing down).
    pub fn ceiling_rect(&mut self, min: DVec2, max: DVec2, z: f64, material: &str) {
        self.file.ceilings.push(RectFile {
            min: min.to_array(),
            max: max.to_array(),
            z,
            material: material.into(),
        });
    }

    /// A closed room outline: a wall along every edge (`walls[i]` from
    /// vertex `i` to `i + 1`; `None` leaves the edge to the caller), with
    /// floor and ceiling polygons.
    pub fn outline(
        &mut self,
        vertices: &[DVec2],
        walls: &[Option<&str>],
        height: f64,
        floor: &str,
        ceiling: &str,
    ) {
        let n = vertices.len();
        for i in 0..n {
            if let Some(m) = walls[i] {
                self.wall(vertices[i], vertices[(i + 1) % n], 0.0, height, m);
            }
        }
        self.slab(vertices, 0.0, floor);
        let mut top = vertices.to_vec();
        top.reverse();
        self.slab(&top, height, ceiling);
    }

    /// A panel (mirror, screen) hung on the wall `a`-`b` between the
    /// fractions `from` and `to` of its length, `base` to `base + height`,
    /// [`PANEL_OFFSET`] in front of it on the side of `inside` (a point).
    #[allow(clippy::too_many_arguments)]
    pub fn panel(
        &mut self,
        a: DVec2,
        b: DVec2,
        from: f64,
        to: f64,
        base: f64,
        height: f64,
        inside: DVec2,
        material: &str,
    ) {
        let along = b - a;
        let mut normal = DVec2::new(-along.y, along.x).normalize();
        if normal.dot(inside - a) < 0.0 {
            normal = -normal;
        }
        let shift = normal * PANEL_OFFSET;
        self.wall(
            a + along * from + shift,
            a + along * to + shift,
            base,
            height,
            material,
        );
    }

    /// A glazed wall from `a` to `b` standing on height `z0`, built as
    /// `g` says. Returns the pane count.
    pub fn glazing(&mut self, a: DVec2, b: DVec2, z0: f64, g: &Glazing<'_>) -> usize {
        let len = a.distance(b);
        let dir = (b - a) / len;
        let panes = ((len + g.mullion) / (g.pane + g.mullion)).round().max(1.0) as usize;
        let width = (len - g.mullion * (panes as f64 - 1.0)) / panes as f64;
        let clear = g.head - g.sill;
        self.wall(a, b, z0, g.sill, g.frame);
        self.wall(a, b, z0 + g.head, g.top - g.head, g.frame);
        let mut s = 0.0;
        for k in 0..panes {
            let p0 = a + dir * s;
            let p1 = a + dir * (s + width);
            self.wall(p0, p1, z0 + g.sill, clear, g.glass);
            s += width;
            if k + 1 < panes {
                self.wall(p1, a + dir * (s + g.mullion), z0 + g.sill, clear, g.frame);
                s += g.mullion;
            }
        }
        panes
    }

    /// A glazed wall with random pane widths (0.6-3 m), mullions
    /// (0.05-0.3 m), sill (below `max_sill`) and head, `top` high.
    pub fn random_glazing(
        &mut self,
        a: DVec2,
        b: DVec2,
        top: f64,
        max_sill: f64,
        glass: &str,
        frame: &str,
    ) -> usize {
        let pane = self.uniform(0.6, 3.0);
        let mullion = self.uniform(0.05, 0.3);
        let sill = if self.chance(0.4) {
            0.0
        } else {
            self.uniform(0.05, max_sill)
        };
        let head = top - self.uniform(0.0, 0.4).min(top * 0.2);
        let g = Glazing {
            sill,
            head,
            top,
            pane,
            mullion,
            glass,
            frame,
        };
        self.glazing(a, b, 0.0, &g)
    }

    // ------------------------------------------------------------ solids

    /// A solid box from `min` to `max` (axis-aligned), unless it overlaps
    /// a solid placed before or comes within [`PATH_CLEARANCE`] of the
    /// sensor's path; returns whether it was placed.
    pub fn solid(&mut self, min: DVec3, max: DVec3, material: &str) -> bool {
        let candidate = Solid { min, max };
        let overlaps = self
            .solids
            .iter()
            .any(|s| super::boxes_overlap((candidate.min, candidate.max), (s.min, s.max)));
        if overlaps || self.near_path(min.truncate(), max.truncate(), PATH_CLEARANCE) {
            return false;
        }
        self.solids.push(candidate);
        self.file.boxes.push(BoxFile {
            min: min.to_array(),
            max: max.to_array(),
            yaw_deg: 0.0,
            material: material.into(),
            omit: vec!["floor".into()],
            sides: BTreeMap::new(),
        });
        true
    }

    /// Keep the box `min`-`max` free of solids placed later (a glass-walled
    /// room whose walls are not solids).
    pub fn reserve(&mut self, min: DVec3, max: DVec3) {
        self.solids.push(Solid { min, max });
    }

    /// A solid box that ignores the path (columns and fixed structure the
    /// path was drawn around).
    pub fn fixed(&mut self, min: DVec3, max: DVec3, material: &str, sides: &[(&str, &str)]) {
        self.solids.push(Solid { min, max });
        self.file.boxes.push(BoxFile {
            min: min.to_array(),
            max: max.to_array(),
            yaw_deg: 0.0,
            material: material.into(),
            omit: vec!["floor".into(), "ceiling".into()],
            sides: sides
                .iter()
                .map(|(s, m)| (s.to_string(), m.to_string()))
                .collect(),
        });
    }

    /// Whether the rectangle `min`-`max` comes within `margin` of the path.
    fn near_path(&self, min: DVec2, max: DVec2, margin: f64) -> bool {
        self.path_samples().any(|p| {
            let d = (min - p).max(p - max).max(DVec2::ZERO);
            d.length() < margin
        })
    }

    /// Points along the (closed) path every 0.1 m.
    fn path_samples(&self) -> impl Iterator<Item = DVec2> + '_ {
        let n = self.path.len();
        (0..n).flat_map(move |i| {
            let a = self.path[i];
            let b = self.path[(i + 1) % n];
            let steps = (a.distance(b) / 0.1).ceil().max(1.0) as usize;
            (0..=steps).map(move |k| a + (b - a) * (k as f64 / steps as f64))
        })
    }

    // --------------------------------------------------------- the path

    /// The sensor's path through floor-plan `points` at a random walking
    /// speed (0.3-1.5 m/s), height and mounting tilt: a loop when
    /// `closed`, else walked there and back on a narrow loop
    /// ([`there_and_back`]), turning at each end as a walker does rather
    /// than spinning on the spot.
    pub fn path(&mut self, points: &[DVec2], closed: bool, floor: f64) {
        let there_back;
        let points = if closed {
            points
        } else {
            there_back = there_and_back(points, TURN_WIDTH);
            &there_back
        };
        let height = floor + self.uniform(0.8, 1.8);
        let speed = self.uniform(0.3, 1.5);
        let tilt = [
            (1.5 * self.rng.normal()).clamp(-4.0, 4.0),
            (1.5 * self.rng.normal()).clamp(-4.0, 4.0),
        ];
        self.path = points.to_vec();
        let t = &mut self.file.trajectory;
        t.waypoints = points.iter().map(|p| [p.x, p.y, height]).collect();
        t.speed = round3(speed);
        t.closed = true;
        t.tilt_deg = Some(tilt.map(round3));
    }

    /// A loop around the rectangle `min`-`max` (its corners, in order).
    pub fn loop_around(&mut self, min: DVec2, max: DVec2, floor: f64) {
        let pts = [min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)];
        self.path(&pts, true, floor);
    }
}

/// Out on one side of the polyline `points` and back on the other, `width`
/// apart: a closed loop whose ends are two right-angle corners `width`
/// apart, which the trajectory's heading smoothing turns into a walker's
/// turn (an open path reversed in place would spin the sensor by 180
/// degrees between two frames).
pub fn there_and_back(points: &[DVec2], width: f64) -> Vec<DVec2> {
    let n = points.len();
    let side = |i: usize| {
        let (a, b) = (points[i.saturating_sub(1)], points[(i + 1).min(n - 1)]);
        let d = (b - a).normalize_or_zero();
        DVec2::new(-d.y, d.x) * (width / 2.0)
    };
    let out = (0..n).map(|i| points[i] + side(i));
    let back = (0..n).rev().map(|i| points[i] - side(i));
    out.chain(back).collect()
}

/// Round to a millimetre (what the scene file shows).
fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}
