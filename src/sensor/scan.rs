//! The organized scan: a frame's points on the sensor's ring × column grid,
//! with both returns of each beam paired (in the sensor frame).

use nalgebra::Vector3;

use crate::cloud::Frame;
use crate::sensor::SensorModel;
use crate::{Error, Result};

/// Marker for "no point" in a cell.
const NONE: u32 = u32::MAX;

/// Both returns of every beam, indexed by (ring, column).
///
/// For a rosette sensor the (ring, column) grid is its spherical grid of
/// directions ([`crate::sensor::rosette`]): a point's cell comes from its
/// direction, not its `ring` field, and the returns of one emission (a
/// return 1 and the returns after it in file order, as the simulator and
/// the Livox driver write them) are paired: the cell keeps the first
/// emission that reaches it, with its last return as return 2; the other
/// emissions in that cell count as collisions.
///
/// Return 1 (first/strongest) and return 2 (last) are kept per cell; a cell
/// whose return 2 was not stored (3DRef stores it only where it differs) has a
/// single return that is both first and last. When two return-1 points fall in
/// the same cell (rare, at bin edges) the first in file order keeps the cell
/// and the other is counted in [`collisions`](Self::collisions).
#[derive(Debug, Clone)]
pub struct OrganizedScan {
    rings: usize,
    columns: usize,
    first: Vec<u32>,
    second: Vec<u32>,
    cell_of_point: Vec<u32>,
    collisions: usize,
}

impl OrganizedScan {
    /// Bytes the scan holds on the heap (for memory budgets).
    pub fn heap_bytes(&self) -> usize {
        4 * (self.first.len() + self.second.len() + self.cell_of_point.len())
    }

    /// Cosine of the angle between point `point`'s beam and the surface it
    /// hit, from its neighbours in the scan (left/right and up/down, the
    /// return of each neighbouring beam nearest in range); `None` where the
    /// neighbours do not span a surface.
    pub fn incidence_cos(&self, frame: &Frame, point: usize) -> Option<f64> {
        let p = frame.points.get(point)?.position();
        let r0 = p.coords.norm();
        let n = self.neighbour_cross(frame, point)?;
        let norm = n.norm();
        if !(norm > 1e-12) || !(r0 > 0.0) {
            return None;
        }
        Some((n.dot(&p.coords) / (norm * r0)).abs())
    }

    /// The unit normal (either sign) of the surface around `point`, from its
    /// neighbours in the scan (the returns of the adjacent columns and rings
    /// nearest to its range, within a tenth of it plus 0.2 m); `None` where
    /// they do not span a surface.
    pub fn local_normal(&self, frame: &Frame, point: usize) -> Option<Vector3<f64>> {
        let n = self.neighbour_cross(frame, point)?;
        let norm = n.norm();
        (norm > 1e-12).then(|| n / norm)
    }

    /// Whether the surface around `point` faces along `normal` (unit)
    /// within `min_cos` (`|n · normal| >= min_cos`): it lies along a plane
    /// of that normal rather than crossing it. `None` where the neighbours
    /// span no surface ([`local_normal`](Self::local_normal)).
    pub fn faces(
        &self,
        frame: &Frame,
        point: usize,
        normal: &Vector3<f64>,
        min_cos: f64,
    ) -> Option<bool> {
        self.local_normal(frame, point)
            .map(|n| n.dot(normal).abs() >= min_cos)
    }

    /// The cross product of the neighbour differences across columns and
    /// rings around `point` (unnormalised).
    fn neighbour_cross(&self, frame: &Frame, point: usize) -> Option<Vector3<f64>> {
        let p = frame.points.get(point)?.position();
        let r0 = p.coords.norm();
        let (ring, col) = self.ring_column(self.cell_of(point));
        let near = |ring: isize, col: isize| {
            if ring < 0 || ring as usize >= self.rings {
                return None;
            }
            let cell = self.cell(ring as usize, col);
            [self.first(cell), self.second(cell)]
                .into_iter()
                .flatten()
                .map(|j| frame.points[j].position())
                .filter(|q| (q.coords.norm() - r0).abs() <= 0.1 * r0 + 0.2)
                .min_by(|a, b| {
                    (a.coords.norm() - r0)
                        .abs()
                        .total_cmp(&(b.coords.norm() - r0).abs())
                })
        };
        let (r, c) = (ring as isize, col as isize);
        let across = near(r, c + 1).unwrap_or(p) - near(r, c - 1).unwrap_or(p);
        let up = near(r + 1, c).unwrap_or(p) - near(r - 1, c).unwrap_or(p);
        Some(across.cross(&up))
    }

    /// Organize `frame` on `sensor`'s grid. Errors (naming the frame) when a
    /// point's ring is outside the sensor's rings.
    pub fn build(frame: &Frame, sensor: &SensorModel) -> Result<Self> {
        if sensor.is_rosette() {
            return Ok(Self::build_by_emission(frame, sensor));
        }
        let mut scan = Self::empty(frame, sensor);
        let (rings, columns) = (scan.rings, scan.columns);
        // Return 1 first, so return 2 can always find its partner cell.
        for pass in [1u8, 2u8] {
            for (i, p) in frame.points.iter().enumerate() {
                // Pass 2 takes every later return (a third one too).
                if (p.ret == 1) != (pass == 1) {
                    continue;
                }
                let ring = p.ring as usize;
                if ring >= rings {
                    return Err(Error::Input(format!(
                        "frame {}: point {i} has ring {ring} but sensor '{}' has {rings} rings",
                        frame.name, sensor.name
                    )));
                }
                let col = sensor.column_of(p.xyz[0] as f64, p.xyz[1] as f64);
                let cell = ring * columns + col;
                scan.cell_of_point[i] = cell as u32;
                let slot = if pass == 1 {
                    &mut scan.first
                } else {
                    &mut scan.second
                };
                if slot[cell] == NONE {
                    slot[cell] = i as u32;
                } else {
                    scan.collisions += 1;
                }
            }
        }
        Ok(scan)
    }

    /// `sensor`'s grid with no point in it yet, sized for `frame`'s points.
    fn empty(frame: &Frame, sensor: &SensorModel) -> Self {
        let (rings, columns) = (sensor.rings(), sensor.columns);
        Self {
            rings,
            columns,
            first: vec![NONE; rings * columns],
            second: vec![NONE; rings * columns],
            cell_of_point: vec![NONE; frame.points.len()],
            collisions: 0,
        }
    }

    /// Organize the points of a rosette sensor on its grid of directions,
    /// pairing the returns of each emission (see the type's doc).
    fn build_by_emission(frame: &Frame, sensor: &SensorModel) -> Self {
        let mut scan = Self::empty(frame, sensor);
        // A later return belongs to the emission before it when it lies
        // along the same direction (within a tenth of a grid cell).
        let cell_deg = sensor.rosette.as_ref().map_or(0.5, |r| r.grid_deg);
        let same_direction = (0.1 * cell_deg).to_radians().cos();
        // The cell the current emission claimed, and its unit direction.
        let mut emission: Option<(usize, Vector3<f64>)> = None;
        for (i, p) in frame.points.iter().enumerate() {
            let q = p.position();
            let dir = q.coords / q.coords.norm().max(1e-12);
            if p.ret <= 1 {
                let cell = grid_cell(sensor, &q);
                scan.cell_of_point[i] = cell as u32;
                emission = (scan.first[cell] == NONE).then_some((cell, dir));
                match emission {
                    Some((c, _)) => scan.first[c] = i as u32,
                    None => scan.collisions += 1,
                }
                continue;
            }
            match emission {
                // The emission's later return, in its cell: the last one
                // is kept.
                Some((c, d)) if d.dot(&dir) >= same_direction => {
                    scan.cell_of_point[i] = c as u32;
                    scan.second[c] = i as u32;
                }
                _ => {
                    scan.cell_of_point[i] = grid_cell(sensor, &q) as u32;
                    scan.collisions += 1;
                }
            }
        }
        scan
    }

    /// Number of rings (rows).
    pub fn rings(&self) -> usize {
        self.rings
    }

    /// Number of columns.
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Points that lost their cell to an earlier point with the same return.
    pub fn collisions(&self) -> usize {
        self.collisions
    }

    /// Flat cell index of (ring, column); the column wraps around the seam.
    #[inline]
    pub fn cell(&self, ring: usize, column: isize) -> usize {
        ring * self.columns + column.rem_euclid(self.columns as isize) as usize
    }

    /// (ring, column) of a flat cell index.
    #[inline]
    pub fn ring_column(&self, cell: usize) -> (usize, usize) {
        (cell / self.columns, cell % self.columns)
    }

    /// Return-1 point index of a cell.
    #[inline]
    pub fn first(&self, cell: usize) -> Option<usize> {
        let i = self.first[cell];
        (i != NONE).then_some(i as usize)
    }

    /// Return-2 point index of a cell (only where it was stored).
    #[inline]
    pub fn second(&self, cell: usize) -> Option<usize> {
        let i = self.second[cell];
        (i != NONE).then_some(i as usize)
    }

    /// The last return of a cell: return 2 when stored, else return 1.
    #[inline]
    pub fn last(&self, cell: usize) -> Option<usize> {
        self.second(cell).or_else(|| self.first(cell))
    }

    /// The cell a point was placed in.
    #[inline]
    pub fn cell_of(&self, point: usize) -> usize {
        self.cell_of_point[point] as usize
    }

    /// The other return of the same beam, when the cell holds two returns and
    /// `point` is one of them.
    #[inline]
    pub fn partner(&self, point: usize) -> Option<usize> {
        let cell = self.cell_of(point);
        let (f, s) = (self.first[cell], self.second[cell]);
        if f == NONE || s == NONE {
            return None;
        }
        if f as usize == point {
            Some(s as usize)
        } else if s as usize == point {
            Some(f as usize)
        } else {
            None
        }
    }

    /// Cells holding both a return 1 and a return 2.
    pub fn dual_cells(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.first
            .iter()
            .zip(&self.second)
            .enumerate()
            .filter(|(_, (f, s))| **f != NONE && **s != NONE)
            .map(|(c, (f, s))| (c, *f as usize, *s as usize))
    }
}

/// The grid cell of a direction: its nearest row (clamped to the field)
/// and its column.
#[inline]
fn grid_cell(sensor: &SensorModel, q: &nalgebra::Point3<f64>) -> usize {
    let ring = sensor
        .ring_of(q)
        .unwrap_or_else(|| if q.z < 0.0 { 0 } else { sensor.rings() - 1 });
    ring * sensor.columns + sensor.column_of(q.x, q.y)
}

/// A frame of one first return per beam of `sensor` (600 columns) where
/// `hit` puts the surface along the beam's unit direction (`None`: no
/// return), out to 20 m: flat scenes for the tests of what the scan's
/// neighbours tell.
#[cfg(test)]
pub(crate) fn surface_frame(
    sensor: &SensorModel,
    name: &str,
    hit: impl Fn(Vector3<f64>) -> Option<Vector3<f64>>,
) -> Frame {
    let mut points = Vec::new();
    for ring in 0..sensor.rings() {
        for col in 0..600 {
            let Some(p) = hit(sensor.beam_direction(ring, col)) else {
                continue;
            };
            if p.norm() > 20.0 {
                continue;
            }
            points.push(crate::cloud::Point {
                xyz: [p.x as f32, p.y as f32, p.z as f32],
                intensity: 10.0,
                ring: ring as u16,
                ret: 1,
                label: 1,
                time: 0.0,
            });
        }
    }
    Frame {
        name: name.into(),
        points,
        ..Frame::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::cloud::test_point as point;

    #[test]
    fn pairs_returns_by_ring_and_column_across_the_seam() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = Frame {
            name: "t".into(),
            stamp: 0.0,
            points: vec![
                point(-5.0, 1e-6, 0.0, 32, 1),  // azimuth +180 deg
                point(-9.0, -1e-6, 0.0, 32, 2), // azimuth -180 deg: same beam
                point(3.0, 0.0, 0.0, 32, 1),
            ],
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        };
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        assert_eq!(scan.partner(0), Some(1));
        assert_eq!(scan.partner(1), Some(0));
        assert_eq!(scan.partner(2), None);
        assert_eq!(scan.dual_cells().count(), 1);
        assert_eq!(scan.last(scan.cell_of(0)), Some(1));
        assert_eq!(scan.last(scan.cell_of(2)), Some(2));
    }

    #[test]
    fn ring_out_of_range_is_an_error() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = Frame {
            name: "bad".into(),
            points: vec![point(1.0, 0.0, 0.0, 64, 1)],
            ..Default::default()
        };
        let e = OrganizedScan::build(&frame, &sensor)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ring 64") && e.contains("64 rings"), "{e}");
    }

    /// The incidence on a flat wall, from the neighbouring beams, matches
    /// the angle between the beam and the wall's normal.
    #[test]
    fn incidence_on_a_flat_wall_matches_the_geometry() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        // The wall y = 4 (normal along y), seen by every beam towards it.
        let frame = surface_frame(&sensor, "wall", |d| (d.y >= 0.2).then(|| d * (4.0 / d.y)));
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let mut checked = 0;
        for (i, pt) in frame.points.iter().enumerate() {
            let Some(cos) = scan.incidence_cos(&frame, i) else {
                continue;
            };
            let p = pt.position();
            let truth = p.y / p.coords.norm();
            assert!((cos - truth).abs() < 0.02, "point {i}: {cos} vs {truth}");
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
    }

    /// Every point of a flat wall with a surface around it faces along the
    /// wall's normal, and none along a normal crossing the wall.
    #[test]
    fn points_of_a_wall_face_along_its_normal() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = surface_frame(&sensor, "wall", |d| (d.y >= 0.2).then(|| d * (4.0 / d.y)));
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let min_cos = 20f64.to_radians().cos();
        let mut checked = 0;
        for i in 0..frame.points.len() {
            let Some(along) = scan.faces(&frame, i, &Vector3::y(), min_cos) else {
                continue;
            };
            assert!(along, "point {i}");
            assert_eq!(scan.faces(&frame, i, &Vector3::z(), min_cos), Some(false));
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
    }
}
