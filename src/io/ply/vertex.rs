//! The vertex properties mapped to point fields, and the checks and
//! messages both body encodings share.

use super::header::Header;
use crate::cloud::Point;

/// What one vertex property feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Slot {
    Skip,
    X,
    Y,
    Z,
    Intensity,
    Ring,
    Return,
    Label,
    /// Per-point time, seconds after the frame's stamp (`float` or
    /// `double`).
    Time,
}

impl Slot {
    /// The property name of the slot (for messages).
    fn name(self) -> &'static str {
        match self {
            Slot::Skip => "?",
            Slot::X => "x",
            Slot::Y => "y",
            Slot::Z => "z",
            Slot::Intensity => "intensity",
            Slot::Ring => "ring",
            Slot::Return => "return",
            Slot::Label => "label",
            Slot::Time => TIME_PROPERTY,
        }
    }
}

/// The name of the optional per-point time property: seconds after the
/// frame's stamp ([`Point::time`]), `float` or `double`.
pub(crate) const TIME_PROPERTY: &str = "time";

/// The vertex properties mapped to point fields.
pub(super) struct VertexLayout {
    /// One slot per vertex property, in file order.
    pub(super) slots: Vec<Slot>,
    /// Property names (for messages), in file order.
    pub(super) names: Vec<String>,
    pub(super) has_labels: bool,
}

impl VertexLayout {
    /// Map the vertex element's properties to slots; an error when a
    /// property 3DRef frames need is missing.
    pub(super) fn new(header: &Header) -> std::result::Result<VertexLayout, String> {
        let el = &header.elements[header.vertex];
        let mut slots = Vec::with_capacity(el.props.len());
        for (_, name) in &el.props {
            slots.push(match name.as_str() {
                "x" => Slot::X,
                "y" => Slot::Y,
                "z" => Slot::Z,
                "intensity" => Slot::Intensity,
                "ring" => Slot::Ring,
                "return" => Slot::Return,
                "label" => Slot::Label,
                TIME_PROPERTY => Slot::Time,
                _ => Slot::Skip,
            });
        }
        // A time is a fraction of a sweep: an integer type cannot hold it.
        if let Some((ty, _)) = el.props.iter().find(|(_, n)| n == TIME_PROPERTY) {
            if !ty.is_float() {
                return Err(format!(
                    "property '{TIME_PROPERTY}' must be float or double (seconds after the frame's stamp), got {}",
                    ty.name()
                ));
            }
        }
        for need in [
            Slot::X,
            Slot::Y,
            Slot::Z,
            Slot::Intensity,
            Slot::Ring,
            Slot::Return,
        ] {
            if !slots.contains(&need) {
                return Err(format!(
                    "header has no '{}' property (3DRef frames need x y z intensity ring return)",
                    need.name()
                ));
            }
        }
        Ok(VertexLayout {
            has_labels: slots.contains(&Slot::Label),
            slots,
            names: el.props.iter().map(|(_, n)| n.clone()).collect(),
        })
    }
}

/// Store a per-point time (seconds after the frame's stamp) into `p`; a
/// NaN or infinite time is an error (unlike a coordinate, it is no
/// driver's placeholder for a missing return).
#[inline(always)]
pub(super) fn store_time(p: &mut Point, v: f64, loc: Loc) -> std::result::Result<(), String> {
    let t = v as f32;
    if t.is_finite() {
        p.time = t;
        Ok(())
    } else {
        Err(bad_time(v, loc))
    }
}

/// The message for a time that is not a finite number of seconds.
#[cold]
fn bad_time(v: f64, loc: Loc) -> String {
    format!("{loc}: {TIME_PROPERTY} must be a finite number of seconds, got {v}")
}

/// Where a vertex is, for messages: "line 17, vertex 5" or "vertex 5".
#[derive(Clone, Copy)]
pub(super) struct Loc {
    pub(super) line: usize,
    pub(super) vertex: usize,
}

impl std::fmt::Display for Loc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "line {}, vertex {}", self.line, self.vertex)
        } else {
            write!(f, "vertex {}", self.vertex)
        }
    }
}

/// Store a non-coordinate value into `p`, validating it.
#[inline(always)]
pub(super) fn store_int(
    p: &mut Point,
    slot: Slot,
    v: f64,
    loc: Loc,
) -> std::result::Result<(), String> {
    // Saturating casts: the value is valid iff it survives the round trip
    // (NaN, negative, fractional and too large values do not).
    match slot {
        Slot::Ring => {
            let r = v as u16;
            if r as f64 == v {
                p.ring = r;
                return Ok(());
            }
        }
        Slot::Return => {
            if v == 1.0 || v == 2.0 || v == 3.0 {
                p.ret = v as u8;
                return Ok(());
            }
        }
        Slot::Label => {
            let l = v as u8;
            if l as f64 == v && l <= 6 {
                p.label = l;
                return Ok(());
            }
        }
        _ => return Ok(()),
    }
    Err(bad_int(slot, v, loc))
}

/// The message for an integer field out of its range.
#[cold]
fn bad_int(slot: Slot, v: f64, loc: Loc) -> String {
    match slot {
        Slot::Ring => format!("{loc}: ring must be an integer in 0..=65535, got {v}"),
        Slot::Return => format!("{loc}: return must be 1, 2 or 3 (a third return: Livox), got {v}"),
        _ => format!("{loc}: label must be an integer in 0..=6, got {v}"),
    }
}

/// The message for a body that ends before its vertices do.
pub(super) fn truncated(expected: usize, got: usize) -> String {
    format!("expected {expected} vertices, file ends after {got} (truncated?)")
}
