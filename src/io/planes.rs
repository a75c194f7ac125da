//! `planes.json`: a plane map (or a simulator's true reflective planes) as a
//! JSON array, one object per landmark, world coordinates.
//!
//! ```json
//! [{ "id": 0, "kind": "reflective", "material": "glass",
//!    "normal": [-0.998, 0.027, 0.049], "d": 4.99,
//!    "hull": [[x, y, z], ...],
//!    "observations": 10, "first_frame": "1689496219.652560", "last_frame": "..." }]
//! ```
//! `normal`/`d` follow the plane convention `n·x + d = 0` with the normal
//! facing the sensors that observed the plane; `hull` is the boundary
//! polygon (counter-clockwise seen from the normal side).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::write_atomic;
use crate::{Error, Result};

/// The kind of a plane landmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlaneKind {
    /// An ordinary (opaque) plane.
    Ordinary,
    /// A reflective plane: glass, mirror or other reflective surface.
    Reflective,
    /// The ground plane.
    Ground,
}

/// One plane of `planes.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlaneRecord {
    /// Landmark id, unique in the file.
    pub id: usize,
    /// Kind.
    pub kind: PlaneKind,
    /// Material when known (`glass`, `mirror`, ...), e.g. from a simulator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Unit normal (world frame).
    pub normal: [f64; 3],
    /// Offset `d` of `n·x + d = 0`.
    pub d: f64,
    /// Boundary vertices, world frame.
    pub hull: Vec<[f64; 3]>,
    /// Number of observations fused into the landmark.
    #[serde(default)]
    pub observations: usize,
    /// Name of the first frame that observed it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_frame: Option<String>,
    /// Name of the last frame that observed it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_frame: Option<String>,
    /// Separate panes (boundaries) on this plane, when known.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub panes: Vec<Vec<[f64; 3]>>,
    /// The probability that a reflective landmark is a mirror rather than
    /// glass, from its echoes over the sequence, when estimated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mirror_probability: Option<f64>,
    /// The share of reflections among the echoes behind a reflective
    /// landmark, where their strengths tell it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflection_share: Option<f64>,
    /// The share of reflections among the echoes behind it that the space
    /// seen directly decided (the prior of a point no test weighs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decided_share: Option<f64>,
}

/// Write `planes.json` (atomically, pretty-printed).
pub fn write_planes(path: &Path, planes: &[PlaneRecord]) -> Result<()> {
    let json = serde_json::to_vec_pretty(planes)
        .map_err(|e| Error::Input(format!("{}: cannot serialise planes: {e}", path.display())))?;
    write_atomic(path, |w| std::io::Write::write_all(w, &json))
}

/// Read `planes.json`.
pub fn read_planes(path: &Path) -> Result<Vec<PlaneRecord>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_slice(&bytes).map_err(|e| Error::format(path, e.to_string()))
}
