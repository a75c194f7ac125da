//! The `PointCloud2` layouts of the LiDAR drivers people record bags with,
//! each a [`FieldMapping`]: which fields it needs, how a record becomes a
//! [`Point`] (position, intensity, ring, return, per-point time) and what
//! only the whole cloud tells (returns paired by order, rings counted from
//! the top).
//!
//! The facts behind each mapping (topics, fields, types, return semantics,
//! time fields, with their sources) are in the project's
//! `reference/sensors.md`; what a mapping *infers* because the driver does
//! not write it is said on its type.
//!
//! | driver | needs | return | ring | per-point time |
//! |---|---|---|---|---|
//! | generic | `x y z` | `return`/`ret` (1 first, 2 last), else 1 | `ring` | `t`/`time`/`timestamp`, unit guessed ([`GenericLayout`]) |
//! | ouster (ouster-ros) | `x y z intensity t ring` | 1 on the first topic, 2 on the second (`/ouster/points2`) | `ring` (row, 0 = top) flipped to 0 = bottom | `t`, ns from scan start |
//! | livox (livox_ros_driver2, livox_ros2_driver) | `x y z intensity tag line` | `tag` bits 5:4 | `line` | `timestamp`, absolute ns (when present) |
//! | hesai (HesaiLidar_ROS_2.0) | `x y z intensity ring timestamp` | inferred: two consecutive points of a ring at one azimuth are one firing's two echoes, the nearer is 1 | `ring` | `timestamp`, absolute s |
//! | nebula (tier4) | `x y z intensity return_type channel` | `return_type` | `channel` | `time_stamp`, ns from scan start |
//!
//! The Livox drivers' other message, `CustomMsg` (`xfer_format = 1`), is
//! not a `PointCloud2`; [`crate::io::livox_custom`] reads it with the same
//! return rule ([`livox_tag_return`]).

use crate::cloud::Point;

use super::cloud::{Cloud, Field};

/// The drivers whose layouts specular reads (chosen on the command line
/// with `--driver`, or detected from the fields, [`Driver::detect`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Driver {
    /// specular's own layout and any cloud with a `return` (or `ret`)
    /// field: [`GenericLayout`].
    Generic,
    /// ouster-ros (ROS 2): [`OusterLayout`].
    Ouster,
    /// livox_ros_driver2 / livox_ros2_driver `PointCloud2`: [`LivoxLayout`].
    Livox,
    /// HesaiLidar_ROS_2.0: [`HesaiLayout`].
    Hesai,
    /// tier4's nebula (`pandar_points`): [`NebulaLayout`].
    Nebula,
}

impl Driver {
    /// Every driver, in the order detection tries them (after `return`).
    pub const ALL: [Driver; 5] = [
        Driver::Generic,
        Driver::Ouster,
        Driver::Livox,
        Driver::Hesai,
        Driver::Nebula,
    ];

    /// The name on the command line (`--driver`).
    pub fn name(self) -> &'static str {
        self.mapping().name()
    }

    /// The driver called `name` ([`Driver::name`]).
    pub fn from_name(name: &str) -> Option<Driver> {
        Driver::ALL.into_iter().find(|d| d.name() == name)
    }

    /// Its field mapping.
    pub fn mapping(self) -> &'static dyn FieldMapping {
        match self {
            Driver::Generic => &GenericLayout,
            Driver::Ouster => &OusterLayout,
            Driver::Livox => &LivoxLayout,
            Driver::Hesai => &HesaiLayout,
            Driver::Nebula => &NebulaLayout,
        }
    }

    /// The layout of `cloud` from its fields: a `return` or `ret` field is
    /// the generic layout; else the first of nebula (`return_type`), Livox
    /// (`tag` and `line`), Ouster (`t`, `ring` and `reflectivity`) and
    /// Hesai (`ring` and `timestamp`) whose telling fields are all there;
    /// else the generic layout (every point a first return).
    pub fn detect(cloud: &Cloud) -> Driver {
        if cloud.has("return") || cloud.has("ret") {
            return Driver::Generic;
        }
        [Driver::Nebula, Driver::Livox, Driver::Ouster, Driver::Hesai]
            .into_iter()
            .find(|d| {
                let m = d.mapping();
                m.required()
                    .iter()
                    .chain(m.telltale())
                    .all(|f| cloud.has(f))
            })
            .unwrap_or(Driver::Generic)
    }
}

impl std::fmt::Display for Driver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How one driver's `PointCloud2` becomes points: one implementation per
/// driver, so a new driver is a new type and a [`Driver`] variant.
pub trait FieldMapping: Sync {
    /// The name on the command line (`--driver`).
    fn name(&self) -> &'static str;
    /// The driver and its point type, for messages.
    fn describe(&self) -> &'static str;
    /// The fields a cloud must have to be read with this mapping.
    fn required(&self) -> &'static [&'static str];
    /// Further fields that tell this layout apart when the driver is not
    /// named ([`Driver::detect`]); not needed to read.
    fn telltale(&self) -> &'static [&'static str] {
        &[]
    }
    /// The per-point reader of `cloud` (which has the required fields).
    fn reader(&self, cloud: &Cloud) -> PointReader;
    /// What only the whole cloud tells, after its points are read in
    /// message order and before any is set aside (returns paired by order,
    /// rings renumbered); an error for a cloud that contradicts the layout.
    fn finish(&self, _cloud: &Cloud, _points: &mut [Point]) -> Result<(), String> {
        Ok(())
    }

    /// An error naming what `cloud` lacks (and what it has) unless it has
    /// every [required](Self::required) field.
    fn check(&self, cloud: &Cloud) -> Result<(), String> {
        let missing: Vec<&str> = self
            .required()
            .iter()
            .copied()
            .filter(|f| !cloud.has(f))
            .collect();
        if missing.is_empty() {
            return Ok(());
        }
        Err(format!(
            "the cloud is not laid out as the {} driver writes it ({}): it lacks the field(s) {}; its fields are {}",
            self.name(),
            self.describe(),
            missing.join(" "),
            cloud.field_names()
        ))
    }
}

/// A per-point time conversion: the raw field value and the header stamp
/// (seconds) to seconds after the stamp.
type TimeOf = fn(f64, f64) -> f64;

/// A return conversion: the raw field value to specular's return index.
type ReturnOf = fn(f64) -> u8;

/// Which field feeds which part of a [`Point`], resolved once per cloud;
/// reading a record allocates nothing.
#[derive(Debug, Clone, Copy)]
pub struct PointReader {
    xyz: [Field; 3],
    intensity: Option<Field>,
    ring: Option<Field>,
    label: Option<Field>,
    ret: Option<(Field, ReturnOf)>,
    time: Option<(Field, TimeOf)>,
}

impl PointReader {
    /// `x y z`, `intensity`, `ring` and `label` where the cloud has them;
    /// no return and no time. `cloud` must have `x y z`.
    fn base(cloud: &Cloud) -> Self {
        let f = |n: &str| cloud.field(n);
        let zero = Field {
            offset: 0,
            datatype: 7,
        };
        Self {
            xyz: [
                f("x").unwrap_or(zero),
                f("y").unwrap_or(zero),
                f("z").unwrap_or(zero),
            ],
            intensity: f("intensity"),
            ring: f("ring"),
            label: f("label"),
            ret: None,
            time: None,
        }
    }

    /// The point of record `rec`; `ret` when the layout has no return
    /// field, `stamp` the header stamp in seconds.
    #[inline]
    pub fn point(&self, rec: &[u8], stamp: f64, ret: u8) -> Point {
        let [x, y, z] = self.xyz;
        Point {
            xyz: [x.read(rec) as f32, y.read(rec) as f32, z.read(rec) as f32],
            intensity: self.intensity.map_or(0.0, |f| f.read(rec) as f32),
            ring: self.ring.map_or(0, |f| f.read(rec) as u16),
            ret: self.ret.map_or(ret, |(f, of)| of(f.read(rec))),
            label: self.label.map_or(0, |f| f.read(rec) as u8),
            time: self
                .time
                .map_or(0.0, |(f, of)| of(f.read(rec), stamp) as f32),
        }
    }
}

/// Nanoseconds (absolute since the epoch, or counted from the header stamp
/// when below 1e15, i.e. before 1970-01-12) to seconds after the stamp.
fn from_ns(raw: f64, stamp: f64) -> f64 {
    if raw.abs() > 1e15 {
        (raw - stamp * 1e9) * 1e-9
    } else {
        raw * 1e-9
    }
}

/// Seconds (absolute when above 1e6, i.e. after 1970-01-12, else counted
/// from the header stamp), or nanoseconds when above 1e15, to seconds after
/// the stamp.
fn from_seconds(raw: f64, stamp: f64) -> f64 {
    if raw.abs() > 1e15 {
        from_ns(raw, stamp)
    } else if raw.abs() > 1e6 {
        raw - stamp
    } else {
        raw
    }
}

/// specular's own layout and any cloud with a `return` (or `ret`) field
/// (1 first, 2 last); without one every point is a first return. `ring`
/// is read as is (0 = bottom). Per-point time comes from `t`, `time` or
/// `timestamp` (the first present, the names KISS-ICP reads); as the unit
/// is not named, it is inferred from the type and size of each value: an
/// integer is nanoseconds, a float seconds, a value above 1e15 is absolute
/// nanoseconds and a float above 1e6 absolute seconds (both taken relative
/// to the header stamp), anything smaller counts from the stamp.
#[derive(Debug, Clone, Copy)]
pub struct GenericLayout;

impl FieldMapping for GenericLayout {
    fn name(&self) -> &'static str {
        "generic"
    }
    fn describe(&self) -> &'static str {
        "x y z [intensity ring return label t|time|timestamp]"
    }
    fn required(&self) -> &'static [&'static str] {
        &["x", "y", "z"]
    }
    fn reader(&self, cloud: &Cloud) -> PointReader {
        let mut r = PointReader::base(cloud);
        let ret = cloud.field("return").or_else(|| cloud.field("ret"));
        r.ret = ret.map(|f| (f, (|v| v as u8) as ReturnOf));
        let time = ["t", "time", "timestamp"]
            .into_iter()
            .find_map(|n| cloud.field(n));
        r.time = time.map(|f| {
            let of: TimeOf = if f.is_integer() {
                from_ns
            } else {
                from_seconds
            };
            (f, of)
        });
        r
    }
}

/// ouster-ros (ROS 2), `point_type: original`: `x y z intensity t
/// reflectivity ring ambient range` (struct-padded; offsets from the
/// fields). Return 1 is published on one topic (`/ouster/points`), return
/// 2 on another (`/ouster/points2`), both organized (height = beams, width
/// = columns, NaN or zero where a beam had no echo) with the same shape, so
/// the record at one index of the two clouds is one beam's two returns;
/// the bag reader pairs the two messages by header stamp and gives this
/// mapping the return of the topic. `t` is nanoseconds from the scan start
/// (the header stamp). `ring` is the row, 0 = the top beam; specular counts
/// rings from the bottom, so ring = rows − 1 − row, rows being the cloud's
/// height (an unorganized cloud: the highest row + 1 rounded up to a power
/// of two, at least 16, as Ouster sensors have 16, 32, 64 or 128 beams).
#[derive(Debug, Clone, Copy)]
pub struct OusterLayout;

impl FieldMapping for OusterLayout {
    fn name(&self) -> &'static str {
        "ouster"
    }
    fn describe(&self) -> &'static str {
        "ouster-ros: x y z intensity t reflectivity ring ambient range"
    }
    fn required(&self) -> &'static [&'static str] {
        &["x", "y", "z", "intensity", "t", "ring"]
    }
    fn telltale(&self) -> &'static [&'static str] {
        &["reflectivity"]
    }
    fn reader(&self, cloud: &Cloud) -> PointReader {
        let mut r = PointReader::base(cloud);
        r.time = cloud.field("t").map(|f| (f, (|v, _| v * 1e-9) as TimeOf));
        r
    }
    fn finish(&self, cloud: &Cloud, points: &mut [Point]) -> Result<(), String> {
        let rows = if cloud.organized() {
            cloud.height
        } else {
            let top = points.iter().map(|p| p.ring as usize).max().unwrap_or(0);
            (top + 1).next_power_of_two().max(16)
        };
        for (i, p) in points.iter_mut().enumerate() {
            let row = p.ring as usize;
            if row >= rows {
                return Err(format!(
                    "point {i} has ring {row} but the organized cloud has {rows} rows"
                ));
            }
            p.ring = (rows - 1 - row) as u16;
        }
        Ok(())
    }
}

/// livox_ros_driver2 (`x y z intensity tag line timestamp`, 26-byte
/// records) and livox_ros2_driver's `xfer_format` 0 (`x y z intensity tag
/// line`, no time; the Avia's ROS 2 driver): unorganized. The return
/// number is `tag` bits 5:4 (Livox manuals: 0 = an echo merged with the
/// window's, i.e. a target nearer than about 1.5 m, 1, 2, 3); 0 and 1 read
/// as return 1, 2 and 3 as return 2 (a later echo of the same pulse; the
/// echoes of one pulse are consecutive). `line` is the ring (the Avia has
/// 6 lines, derived by the driver). `timestamp` (float64) is absolute
/// nanoseconds (or nanoseconds from the header stamp when below 1e15).
#[derive(Debug, Clone, Copy)]
pub struct LivoxLayout;

impl FieldMapping for LivoxLayout {
    fn name(&self) -> &'static str {
        "livox"
    }
    fn describe(&self) -> &'static str {
        "livox_ros_driver2: x y z intensity tag line timestamp"
    }
    fn required(&self) -> &'static [&'static str] {
        &["x", "y", "z", "intensity", "tag", "line"]
    }
    fn reader(&self, cloud: &Cloud) -> PointReader {
        let mut r = PointReader::base(cloud);
        r.ring = cloud.field("line");
        r.ret = cloud.field("tag").map(|f| (f, livox_return as ReturnOf));
        r.time = cloud.field("timestamp").map(|f| (f, from_ns as TimeOf));
        r
    }
}

/// The return of a Livox `tag` field's value ([`livox_tag_return`]).
fn livox_return(tag: f64) -> u8 {
    livox_tag_return(tag as u8)
}

/// specular's return of a Livox `tag` byte, for the `PointCloud2` layout
/// ([`LivoxLayout`]) and the `CustomMsg` ([`crate::io::livox_custom`])
/// alike: bits 5:4 hold the echo number; 0 (an echo merged with the
/// window's, a target nearer than about 1.5 m) and 1 are return 1, 2 and
/// 3 are return 2 (a later echo of the same pulse).
pub fn livox_tag_return(tag: u8) -> u8 {
    if (tag >> 4) & 3 >= 2 {
        2
    } else {
        1
    }
}

/// The most two echoes of one firing may differ in azimuth, degrees: half
/// the QT64's 0.6 deg column (both are written at the firing's azimuth).
pub const HESAI_SAME_AZIMUTH_DEG: f64 = 0.3;

/// HesaiLidar_ROS_2.0 (`/lidar_points`: `x y z intensity` float32, `ring`
/// uint16, `timestamp` float64 absolute seconds), unorganized, with both
/// returns of a dual-return mode in one cloud and **no return index**.
/// What is inferred: the sensor sends a firing's two echoes in adjacent
/// blocks at one azimuth (Pandar QT manual) and the driver writes them in
/// that order, so a point whose ring's previous point (in message order,
/// not already paired) lies within [`HESAI_SAME_AZIMUTH_DEG`] of its
/// azimuth is the other echo of that firing. Of the pair the nearer is
/// return 1 and the farther return 2 (first and last, the QT64's dual
/// mode); a second echo at exactly the first's position is the same echo
/// written twice and is set aside (3DRef stores return 2 only where it
/// differs). A point without such a partner is return 1. With
/// `echo_mode_filter` keeping one echo, or a single-return mode, every
/// point is return 1. If the driver dropped one echo of a firing and the
/// next firing's first echo landed within the tolerance, the two would be
/// paired wrongly: this cannot be told from the cloud.
#[derive(Debug, Clone, Copy)]
pub struct HesaiLayout;

impl FieldMapping for HesaiLayout {
    fn name(&self) -> &'static str {
        "hesai"
    }
    fn describe(&self) -> &'static str {
        "HesaiLidar_ROS_2.0: x y z intensity ring timestamp"
    }
    fn required(&self) -> &'static [&'static str] {
        &["x", "y", "z", "intensity", "ring", "timestamp"]
    }
    fn reader(&self, cloud: &Cloud) -> PointReader {
        let mut r = PointReader::base(cloud);
        r.time = cloud
            .field("timestamp")
            .map(|f| (f, from_seconds as TimeOf));
        r
    }
    fn finish(&self, _cloud: &Cloud, points: &mut [Point]) -> Result<(), String> {
        super::pairing::pair_by_order(points, HESAI_SAME_AZIMUTH_DEG);
        Ok(())
    }
}

/// tier4's nebula (`pandar_points`, PointXYZIRCAEDT: `x y z` float32,
/// `intensity` uint8, `return_type` uint8, `channel` uint16, `azimuth
/// elevation distance` float32, `time_stamp` uint32 ns from the scan start,
/// the header stamp). `return_type` (nebula's ReturnType): LAST (1),
/// LAST_WEAK (5), SECOND (7) and SECONDSTRONGEST (8) are return 2; FIRST
/// (2), STRONGEST (3), FIRST_WEAK (4), IDENTICAL (6, nebula keeps one copy),
/// FIRST_STRONGEST (9), LAST_STRONGEST (10) and UNKNOWN (0) return 1. A cloud
/// without any return-1 point is a single-return mode (e.g. Last): all its
/// points are return 1. `channel` is the ring (QT64 laser 1, the bottom
/// one, is channel 0).
#[derive(Debug, Clone, Copy)]
pub struct NebulaLayout;

impl FieldMapping for NebulaLayout {
    fn name(&self) -> &'static str {
        "nebula"
    }
    fn describe(&self) -> &'static str {
        "nebula PointXYZIRCAEDT: x y z intensity return_type channel azimuth elevation distance time_stamp"
    }
    fn required(&self) -> &'static [&'static str] {
        &["x", "y", "z", "intensity", "return_type", "channel"]
    }
    fn reader(&self, cloud: &Cloud) -> PointReader {
        let mut r = PointReader::base(cloud);
        r.ring = cloud.field("channel");
        r.ret = cloud
            .field("return_type")
            .map(|f| (f, nebula_return as ReturnOf));
        r.time = cloud
            .field("time_stamp")
            .map(|f| (f, (|v, _| v * 1e-9) as TimeOf));
        r
    }
    fn finish(&self, _cloud: &Cloud, points: &mut [Point]) -> Result<(), String> {
        if !points.iter().any(|p| p.ret == 1) {
            points.iter_mut().for_each(|p| p.ret = 1);
        }
        Ok(())
    }
}

/// specular's return of a nebula `return_type`.
fn nebula_return(t: f64) -> u8 {
    match t as u8 {
        1 | 5 | 7 | 8 => 2,
        _ => 1,
    }
}
