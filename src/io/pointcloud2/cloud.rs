//! One CDR `sensor_msgs/msg/PointCloud2` parsed into its header, shape,
//! fields and point records, without reading a point: what every driver's
//! mapping reads from ([`super::drivers`]).

use std::fmt::Write as _;

use crate::io::cdr::CdrReader;

/// One field of a point record: where it is and its `sensor_msgs/PointField`
/// datatype (1 INT8, 2 UINT8, 3 INT16, 4 UINT16, 5 INT32, 6 UINT32,
/// 7 FLOAT32, 8 FLOAT64).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    /// Byte offset in the point record.
    pub offset: usize,
    /// `PointField` datatype, 1..=8.
    pub datatype: u8,
}

impl Field {
    /// Bytes the value takes.
    pub fn size(&self) -> usize {
        match self.datatype {
            1 | 2 => 1,
            3 | 4 => 2,
            5..=7 => 4,
            _ => 8,
        }
    }

    /// Whether the datatype is an integer (not FLOAT32 or FLOAT64).
    pub fn is_integer(&self) -> bool {
        self.datatype <= 6
    }

    /// The value in `rec` (a point record at least `offset + size` long,
    /// which [`Cloud::parse`] checks for every field), as `f64`.
    #[inline]
    pub fn read(&self, rec: &[u8]) -> f64 {
        let b = &rec[self.offset..self.offset + self.size()];
        match self.datatype {
            1 => b[0] as i8 as f64,
            2 => b[0] as f64,
            3 => i16::from_le_bytes([b[0], b[1]]) as f64,
            4 => u16::from_le_bytes([b[0], b[1]]) as f64,
            5 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            6 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            7 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

/// A parsed `PointCloud2`: header stamp, shape, fields and the bytes of its
/// `height × width` point records.
#[derive(Debug, Clone)]
pub struct Cloud<'a> {
    /// Header stamp, whole seconds.
    pub sec: i32,
    /// Header stamp, nanoseconds.
    pub nanosec: u32,
    /// Rows: 1 for an unorganized cloud, the beams for an organized one.
    pub height: usize,
    /// Points per row.
    pub width: usize,
    /// The fields, in message order.
    pub fields: Vec<(String, Field)>,
    /// Bytes per point record.
    pub point_step: usize,
    body: &'a [u8],
}

impl<'a> Cloud<'a> {
    /// Parse the CDR message `data`; an error for a truncated or
    /// inconsistent message (a field beyond the record, records beyond the
    /// data, an unknown datatype, big-endian data).
    pub fn parse(data: &'a [u8]) -> Result<Self, String> {
        let mut c = CdrReader::new(data)?;
        let sec = c.u32()? as i32;
        let nanosec = c.u32()?;
        let _frame_id = c.string()?;
        let height = c.u32()? as usize;
        let width = c.u32()? as usize;
        let n_fields = c.u32()? as usize;
        let mut fields = Vec::with_capacity(n_fields.min(64));
        for _ in 0..n_fields.min(1024) {
            let name = c.string()?;
            let offset = c.u32()? as usize;
            let datatype = c.u8()?;
            let _count = c.u32()?;
            if !(1..=8).contains(&datatype) {
                return Err(format!("field {name}: unknown datatype {datatype}"));
            }
            fields.push((name, Field { offset, datatype }));
        }
        if c.u8()? != 0 {
            return Err("big-endian point data is not supported".into());
        }
        let point_step = c.u32()? as usize;
        let _row_step = c.u32()?;
        let n = c.u32()? as usize;
        let body = c.take(n, 1)?;
        height
            .checked_mul(width)
            .filter(|&k| k.checked_mul(point_step).is_some_and(|b| b <= body.len()))
            .ok_or_else(|| {
                format!("{height}x{width} points of {point_step} bytes exceed the data ({n} bytes)")
            })?;
        for (name, f) in &fields {
            if f.offset + f.size() > point_step {
                return Err(format!("field {name} ends beyond point_step {point_step}"));
            }
        }
        Ok(Self {
            sec,
            nanosec,
            height,
            width,
            fields,
            point_step,
            body,
        })
    }

    /// The field called `name`, if the cloud has it.
    pub fn field(&self, name: &str) -> Option<Field> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, f)| *f)
    }

    /// Whether the cloud has a field called `name`.
    pub fn has(&self, name: &str) -> bool {
        self.field(name).is_some()
    }

    /// The header stamp in seconds.
    pub fn stamp(&self) -> f64 {
        self.sec as f64 + self.nanosec as f64 * 1e-9
    }

    /// Number of point records (`height × width`).
    pub fn len(&self) -> usize {
        self.height * self.width
    }

    /// Whether the cloud has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the cloud is organized (more than one row: rows are beams).
    pub fn organized(&self) -> bool {
        self.height > 1
    }

    /// The point records, in message order (row by row).
    pub fn records(&self) -> impl Iterator<Item = &'a [u8]> + '_ {
        self.body
            .chunks_exact(self.point_step.max(1))
            .take(if self.point_step == 0 { 0 } else { self.len() })
    }

    /// The field names, space-separated (for messages).
    pub fn field_names(&self) -> String {
        let mut s = String::new();
        for (i, (name, _)) in self.fields.iter().enumerate() {
            let _ = write!(s, "{}{name}", if i == 0 { "" } else { " " });
        }
        s
    }
}
