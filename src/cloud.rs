//! The in-memory LiDAR frame: both returns of one revolution in the sensor
//! frame, in file order (predictions are written in the same order).

/// One LiDAR return as stored in a 3DRef frame.
///
/// Bulk storage is `f32` (as the files are); geometry converts to `f64`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// Position in the sensor frame, metres.
    pub xyz: [f32; 3],
    /// Return intensity as reported by the sensor (0-255 for the QT64).
    pub intensity: f32,
    /// Laser ring, 0 at the bottom.
    pub ring: u16,
    /// Return index: 1 = first/strongest, 2 = last.
    pub ret: u8,
    /// 3DRef label id (0 when the file carries no labels).
    pub label: u8,
    /// When the point was measured: seconds after the frame's
    /// [`stamp`](Frame::stamp) (negative when before it), as a bag's
    /// per-point time field gives it (Ouster `t`, Hesai and Livox
    /// `timestamp`, nebula `time_stamp`, or a generic `t`/`time`/`timestamp`;
    /// see [`crate::io::pointcloud2::drivers`]), or a PLY frame's `time`
    /// property (the sweeping simulator writes it). 0 when the source has
    /// no per-point time (3DRef's PLY frames, the instantaneous
    /// simulator): the whole frame is taken at its stamp. Deskewing
    /// ([`crate::slam::deskew`]) reads it.
    pub time: f32,
}

impl Point {
    /// Position as an `f64` point.
    #[inline]
    pub fn position(&self) -> nalgebra::Point3<f64> {
        nalgebra::Point3::new(self.xyz[0] as f64, self.xyz[1] as f64, self.xyz[2] as f64)
    }

    /// Distance from the sensor origin.
    #[inline]
    pub fn range(&self) -> f64 {
        self.position().coords.norm()
    }

    /// Whether the position and the intensity are all finite (no NaN, no
    /// infinity).
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.xyz[0].is_finite()
            && self.xyz[1].is_finite()
            && self.xyz[2].is_finite()
            && self.intensity.is_finite()
    }

    /// Whether the point can be a return: [finite](Self::is_finite), not
    /// exactly at the sensor origin (drivers write `(0, 0, 0)` for a beam
    /// without an echo; no surface is measured at range 0), and no
    /// coordinate beyond [`MAX_RETURN_COORDINATE`] (a float's 3e38 is a
    /// placeholder, not a measurement). The points the readers keep (see
    /// [`drop_non_finite`]).
    #[inline]
    pub fn is_return(&self) -> bool {
        self.is_finite()
            && self.xyz != [0.0; 3]
            && self.xyz.iter().all(|c| c.abs() <= MAX_RETURN_COORDINATE)
    }
}

/// Metres: a coordinate farther from the sensor cannot be a LiDAR return
/// (1,000 km; the longest-range LiDARs reach a few km), so such a point is
/// set aside like a NaN one ([`Point::is_return`]).
pub const MAX_RETURN_COORDINATE: f32 = 1e6;

/// The input points a reader set aside because they cannot be returns
/// (not [`Point::is_return`]): where they were in the input and their
/// labels. Outputs are written one entry per *input* point, so the
/// classes of the points kept are scattered back to input order with
/// these positions (label 0 where a point was set aside,
/// [`SetAside::scatter`]), and scores count these points as unclassified
/// ([`SetAside::labels`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SetAside {
    /// Input positions (0-based, increasing) of the points set aside.
    pub positions: Vec<u32>,
    /// Their ground-truth labels (0 when the frame has none), same order.
    pub labels: Vec<u8>,
}

impl SetAside {
    /// Whether no point was set aside.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Number of points set aside.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Values per input point: `kept` (one per kept point, in order) with
    /// `fill` at every position set aside. The result has
    /// `kept.len() + self.len()` entries.
    pub fn scatter<T: Copy>(&self, kept: &[T], fill: T) -> Vec<T> {
        if self.positions.is_empty() {
            return kept.to_vec();
        }
        let total = kept.len() + self.positions.len();
        let mut out = Vec::with_capacity(total);
        let mut next = self.positions.iter().peekable();
        let mut kept = kept.iter();
        for i in 0..total {
            if next.peek().is_some_and(|&&p| p as usize == i) {
                next.next();
                out.push(fill);
            } else if let Some(&v) = kept.next() {
                out.push(v);
            }
        }
        out
    }

    /// The ground-truth labels per input point: `kept` (the kept points'
    /// labels) with each point set aside's own label at its position.
    pub fn scatter_labels(&self, kept: &[u8]) -> Vec<u8> {
        let mut out = self.scatter(kept, 0);
        for (&p, &l) in self.positions.iter().zip(&self.labels) {
            if let Some(slot) = out.get_mut(p as usize) {
                *slot = l;
            }
        }
        out
    }
}

/// Remove the points that cannot be returns ([`Point::is_return`]: not
/// finite, or exactly at the origin), keeping the order of the others, and
/// say where they were ([`SetAside`]).
pub fn set_aside_non_returns(points: &mut Vec<Point>) -> SetAside {
    if points.iter().all(Point::is_return) {
        return SetAside::default();
    }
    let mut aside = SetAside::default();
    let mut i = 0u32;
    points.retain(|p| {
        let keep = p.is_return();
        if !keep {
            aside.positions.push(i);
            aside.labels.push(p.label);
        }
        i += 1;
        keep
    });
    aside
}

/// Remove the points that cannot be returns ([`Point::is_return`]: not
/// finite, or exactly at the origin), keeping the order of the others (and
/// so their alignment with anything read in the same order, such as their
/// labels); returns how many were removed.
///
/// Every reader (PLY, ROS 2 bag) applies it (through
/// [`set_aside_non_returns`], which also says where they were), so such a
/// point is treated the same whatever its source: set aside and counted in
/// [`Frame::dropped_non_finite`], never classified, and written with label
/// 0 at its input position.
pub fn drop_non_finite(points: &mut Vec<Point>) -> usize {
    set_aside_non_returns(points).len()
}

/// What a return's intensity measures, which decides how it falls with
/// range: an echo's received power falls with the square of the range,
/// and a sensor that reports a calibrated reflectivity has divided that
/// out (the Hesai QT64 in 3DRef: `scripts/intensity-vs-range.sh`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntensityScale {
    /// A reflectivity, range-compensated by the sensor (most drivers).
    #[default]
    Reflectivity,
    /// The received power, falling with r² (specular's simulator).
    RawPower,
}

impl IntensityScale {
    /// The power of the range that turns an intensity of this scale into
    /// a reflectivity (`I · r^k`): 0 for a reflectivity, 2 for a raw power.
    pub fn range_exponent(self) -> f64 {
        match self {
            IntensityScale::Reflectivity => 0.0,
            IntensityScale::RawPower => 2.0,
        }
    }

    /// The name used in sensor files and PLY comments.
    pub fn name(self) -> &'static str {
        match self {
            IntensityScale::Reflectivity => "reflectivity",
            IntensityScale::RawPower => "raw-power",
        }
    }

    /// The scale called `name` ([`IntensityScale::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        [IntensityScale::Reflectivity, IntensityScale::RawPower]
            .into_iter()
            .find(|s| s.name() == name)
    }
}

/// One frame: a revolution of the sensor with both returns.
#[derive(Debug, Clone, Default)]
pub struct Frame {
    /// File stem, e.g. `1689496219.652560`; predictions are named after it.
    pub name: String,
    /// Timestamp in seconds (the stem parsed as a number).
    pub stamp: f64,
    /// All points in input order.
    pub points: Vec<Point>,
    /// Whether the source carried ground-truth labels.
    pub has_labels: bool,
    /// Points the reader set aside because a coordinate (x, y or z) or the
    /// intensity was NaN or infinite, or the point lay exactly at the
    /// origin or impossibly far ([`Point::is_return`]). Real drivers publish such points for
    /// beams without a return (ROS 2 `PointCloud2` with `is_dense = false`);
    /// they have no position to classify or map, so they are never in
    /// [`points`](Self::points). Where they were is kept by the source
    /// ([`Dataset::set_aside`](crate::io::Dataset::set_aside)), so outputs
    /// still carry one label per input point (0 for these). 0 for frames
    /// built in memory.
    pub dropped_non_finite: usize,
    /// What its intensities measure, when the source says (a PLY comment
    /// `intensity_scale raw-power`, the simulator); `None` leaves it to the
    /// sensor model ([`SensorModel::intensity`](crate::sensor::SensorModel::intensity)).
    pub intensity_scale: Option<IntensityScale>,
}

impl Frame {
    /// Ground-truth labels in input order (all 0 when the frame has none).
    pub fn labels(&self) -> Vec<u8> {
        self.points.iter().map(|p| p.label).collect()
    }

    /// Number of second-return points.
    pub fn second_returns(&self) -> usize {
        self.points.iter().filter(|p| p.ret == 2).count()
    }
}

/// Test helper: a labelled-normal point of intensity 10 (shared by the unit
/// tests that build small frames by hand).
#[cfg(test)]
pub(crate) fn test_point(x: f32, y: f32, z: f32, ring: u16, ret: u8) -> Point {
    Point {
        xyz: [x, y, z],
        intensity: 10.0,
        ring,
        ret,
        label: 1,
        time: 0.0,
    }
}
