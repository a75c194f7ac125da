//! The graph file format (JSON, versioned; documented in
//! `docs/graph-format.md`): poses as `t` + quaternion `q = [x, y, z, w]`,
//! planes as `n` + `d`, factors as records with `type`, `keys`,
//! `measurement`, row-major `sqrt_info` and an optional `robust` kernel.
//!
//! Records are plain serde structs converted to and from the runtime types,
//! so the file layout can evolve (through `version`) independently of them.

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Matrix6, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::factors::{AnyFactor, Between, GraphFactor, PlaneObservation, PointToPlane, PosePrior};
use super::graph::FactorGraph;
use super::robust::RobustKernel;
use super::variables::{Key, PlaneVar, Values};
use crate::io::atomic::write_atomic;
use crate::{Error, Result};

/// The `format` field of every graph file.
pub const FORMAT_NAME: &str = "specular-factor-graph";
/// The current (and only) format version.
pub const FORMAT_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GraphFile {
    format: String,
    version: u32,
    #[serde(default = "yes")]
    auto_gauge: bool,
    #[serde(default)]
    fixed: Vec<Key>,
    poses: Vec<PoseRecord>,
    planes: Vec<PlaneRecord>,
    factors: Vec<FactorRecord>,
}

fn yes() -> bool {
    true
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseRecord {
    id: u32,
    t: [f64; 3],
    q: [f64; 4],
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneRecord {
    id: u32,
    n: [f64; 3],
    d: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseMeasurement {
    t: [f64; 3],
    q: [f64; 4],
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneMeasurement {
    n: [f64; 3],
    d: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScatterMeasurement {
    count: f64,
    centroid: [f64; 3],
    scatter: [f64; 9],
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum FactorRecord {
    PosePrior {
        keys: Vec<Key>,
        measurement: PoseMeasurement,
        sqrt_info: Vec<f64>,
        #[serde(default, skip_serializing_if = "is_none_kernel")]
        robust: RobustKernel,
    },
    Between {
        keys: Vec<Key>,
        measurement: PoseMeasurement,
        sqrt_info: Vec<f64>,
        #[serde(default, skip_serializing_if = "is_none_kernel")]
        robust: RobustKernel,
    },
    PlaneObservation {
        keys: Vec<Key>,
        measurement: PlaneMeasurement,
        sqrt_info: Vec<f64>,
        #[serde(default, skip_serializing_if = "is_none_kernel")]
        robust: RobustKernel,
    },
    /// `sqrt_info` is the single number `1/σ` (σ = point noise, metres).
    PointToPlane {
        keys: Vec<Key>,
        measurement: ScatterMeasurement,
        sqrt_info: Vec<f64>,
        #[serde(default, skip_serializing_if = "is_none_kernel")]
        robust: RobustKernel,
    },
}

fn is_none_kernel(k: &RobustKernel) -> bool {
    *k == RobustKernel::None
}

/// Read and validate a graph file.
pub fn read(path: &Path) -> Result<FactorGraph> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file: GraphFile =
        serde_json::from_str(&text).map_err(|e| Error::format(path, e.to_string()))?;
    from_file(file).map_err(|e| match e {
        Error::Input(m) => Error::format(path, m),
        other => other,
    })
}

/// Write a graph file atomically.
pub fn write(graph: &FactorGraph, path: &Path) -> Result<()> {
    let file = to_file(graph);
    write_atomic(path, |w| {
        serde_json::to_writer(&mut *w, &file).map_err(std::io::Error::other)?;
        std::io::Write::write_all(w, b"\n")
    })
}

fn from_file(file: GraphFile) -> Result<FactorGraph> {
    if file.format != FORMAT_NAME {
        return Err(Error::Input(format!(
            "format is '{}', expected '{FORMAT_NAME}'",
            crate::error::excerpt(&file.format)
        )));
    }
    if file.version != FORMAT_VERSION {
        return Err(Error::Input(format!(
            "version {} is not supported (this build reads version {FORMAT_VERSION})",
            file.version
        )));
    }
    let mut values = Values::default();
    for p in &file.poses {
        let pose = pose_from(&p.t, &p.q).ok_or_else(|| bad(format!("pose x{}", p.id)))?;
        if values.poses.insert(p.id, pose).is_some() {
            return Err(Error::Input(format!("pose x{} is listed twice", p.id)));
        }
    }
    for p in &file.planes {
        let plane = plane_from(&p.n, p.d).ok_or_else(|| bad(format!("plane p{}", p.id)))?;
        if values.planes.insert(p.id, plane).is_some() {
            return Err(Error::Input(format!("plane p{} is listed twice", p.id)));
        }
    }
    let mut factors = Vec::with_capacity(file.factors.len());
    for (i, rec) in file.factors.into_iter().enumerate() {
        let f = factor_from(rec).map_err(|e| Error::Input(format!("factor {i}: {e}")))?;
        factors.push(f);
    }
    let graph = FactorGraph {
        values,
        factors,
        fixed: file.fixed.into_iter().collect(),
        auto_gauge: file.auto_gauge,
    };
    graph.validate()?;
    Ok(graph)
}

fn bad(what: String) -> Error {
    Error::Input(format!(
        "{what}: non-finite number or zero-length quaternion/normal"
    ))
}

fn pose_from(t: &[f64; 3], q: &[f64; 4]) -> Option<Isometry3<f64>> {
    if !t.iter().chain(q).all(|v| v.is_finite()) {
        return None;
    }
    let quat = Quaternion::new(q[3], q[0], q[1], q[2]);
    let norm = quat.norm();
    if !(norm > 1e-12) {
        return None;
    }
    // Keep the stored bits when already unit, so a round trip is exact.
    let unit = if (norm - 1.0).abs() < 1e-12 {
        UnitQuaternion::new_unchecked(quat)
    } else {
        UnitQuaternion::new_normalize(quat)
    };
    Some(Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        unit,
    ))
}

fn plane_from(n: &[f64; 3], d: f64) -> Option<PlaneVar> {
    let v = Vector3::from(*n);
    let norm = v.norm();
    if !(norm > 1e-12) || !norm.is_finite() || !d.is_finite() {
        return None;
    }
    if (norm - 1.0).abs() < 1e-12 {
        Some(PlaneVar { normal: v, d })
    } else {
        PlaneVar::new(v, d)
    }
}

fn keys_of<const N: usize>(keys: &[Key], kinds: [&str; N]) -> Result<[u32; N]> {
    if keys.len() != N {
        return Err(Error::Input(format!(
            "expected {N} keys, got {}",
            keys.len()
        )));
    }
    let mut out = [0u32; N];
    for (i, (k, kind)) in keys.iter().zip(kinds).enumerate() {
        out[i] = match (k, kind) {
            (Key::Pose(id), "pose") | (Key::Plane(id), "plane") => *id,
            _ => return Err(Error::Input(format!("key {i} ({k}) must be a {kind}"))),
        };
    }
    Ok(out)
}

fn matrix_from<const N: usize>(v: &[f64]) -> Result<nalgebra::SMatrix<f64, N, N>> {
    if v.len() != N * N || !v.iter().all(|x| x.is_finite()) {
        return Err(Error::Input(format!(
            "sqrt_info must hold {} finite numbers (row-major {N}x{N}), got {}",
            N * N,
            v.len()
        )));
    }
    Ok(nalgebra::SMatrix::<f64, N, N>::from_row_slice(v))
}

fn factor_from(rec: FactorRecord) -> Result<GraphFactor> {
    let (factor, robust) = match rec {
        FactorRecord::PosePrior {
            keys,
            measurement: m,
            sqrt_info,
            robust,
        } => {
            let [i] = keys_of(&keys, ["pose"])?;
            let prior = pose_from(&m.t, &m.q).ok_or_else(|| bad("measurement".into()))?;
            let s: Matrix6<f64> = matrix_from(&sqrt_info)?;
            (AnyFactor::PosePrior(PosePrior::new(i, prior, s)), robust)
        }
        FactorRecord::Between {
            keys,
            measurement: m,
            sqrt_info,
            robust,
        } => {
            let [i, j] = keys_of(&keys, ["pose", "pose"])?;
            let z = pose_from(&m.t, &m.q).ok_or_else(|| bad("measurement".into()))?;
            let s: Matrix6<f64> = matrix_from(&sqrt_info)?;
            (AnyFactor::Between(Between::new(i, j, z, s)), robust)
        }
        FactorRecord::PlaneObservation {
            keys,
            measurement: m,
            sqrt_info,
            robust,
        } => {
            let [x, p] = keys_of(&keys, ["pose", "plane"])?;
            let plane = plane_from(&m.n, m.d).ok_or_else(|| bad("measurement".into()))?;
            let s: Matrix3<f64> = matrix_from(&sqrt_info)?;
            (
                AnyFactor::PlaneObservation(PlaneObservation::new(x, p, plane.plane(), s)),
                robust,
            )
        }
        FactorRecord::PointToPlane {
            keys,
            measurement: m,
            sqrt_info,
            robust,
        } => {
            let [x, p] = keys_of(&keys, ["pose", "plane"])?;
            let inv_sigma = match sqrt_info.as_slice() {
                [v] if v.is_finite() && *v > 0.0 => *v,
                _ => {
                    return Err(Error::Input(
                        "point_to_plane sqrt_info must be one positive number (1/sigma)".into(),
                    ))
                }
            };
            let f = PointToPlane::new(
                x,
                p,
                m.count,
                Vector3::from(m.centroid),
                Matrix3::from_row_slice(&m.scatter),
                1.0 / inv_sigma,
            )?;
            (AnyFactor::PointToPlane(f), robust)
        }
    };
    robust.validate()?;
    Ok(GraphFactor { factor, robust })
}

fn pose_measurement(x: &Isometry3<f64>) -> PoseMeasurement {
    let q = x.rotation.coords;
    PoseMeasurement {
        t: x.translation.vector.into(),
        q: [q.x, q.y, q.z, q.w],
    }
}

fn row_major<const N: usize>(m: &nalgebra::SMatrix<f64, N, N>) -> Vec<f64> {
    (0..N)
        .flat_map(|r| (0..N).map(move |c| m[(r, c)]))
        .collect()
}

fn row_major3(m: &Matrix3<f64>) -> [f64; 9] {
    let mut out = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            out[3 * r + c] = m[(r, c)];
        }
    }
    out
}

fn to_file(graph: &FactorGraph) -> GraphFile {
    let poses = graph
        .values
        .poses
        .iter()
        .map(|(&id, x)| {
            let m = pose_measurement(x);
            PoseRecord { id, t: m.t, q: m.q }
        })
        .collect();
    let planes = graph
        .values
        .planes
        .iter()
        .map(|(&id, p)| PlaneRecord {
            id,
            n: p.normal.into(),
            d: p.d,
        })
        .collect();
    let factors = graph
        .factors
        .iter()
        .map(|f| {
            let robust = f.robust;
            use super::factors::Factor;
            let keys = f.factor.keys().to_vec();
            match &f.factor {
                AnyFactor::PosePrior(p) => FactorRecord::PosePrior {
                    keys,
                    measurement: pose_measurement(&p.prior),
                    sqrt_info: row_major(&p.sqrt_info),
                    robust,
                },
                AnyFactor::Between(b) => FactorRecord::Between {
                    keys,
                    measurement: pose_measurement(&b.measured),
                    sqrt_info: row_major(&b.sqrt_info),
                    robust,
                },
                AnyFactor::PlaneObservation(o) => FactorRecord::PlaneObservation {
                    keys,
                    measurement: PlaneMeasurement {
                        n: o.measured.normal.into(),
                        d: o.measured.d,
                    },
                    sqrt_info: row_major(&o.sqrt_info),
                    robust,
                },
                AnyFactor::PointToPlane(o) => FactorRecord::PointToPlane {
                    keys,
                    measurement: ScatterMeasurement {
                        count: o.count,
                        centroid: o.centroid.into(),
                        scatter: row_major3(&o.scatter),
                    },
                    sqrt_info: vec![1.0 / o.sigma],
                    robust,
                },
            }
        })
        .collect();
    GraphFile {
        format: FORMAT_NAME.into(),
        version: FORMAT_VERSION,
        auto_gauge: graph.auto_gauge,
        fixed: graph.fixed.iter().copied().collect(),
        poses,
        planes,
        factors,
    }
}

/// The graph file format as methods of the graph (this module owns the
/// format; the graph does not depend on it).
impl FactorGraph {
    /// Read a graph file (JSON, see `docs/graph-format.md`); errors name the
    /// file.
    pub fn read(path: &Path) -> Result<Self> {
        read(path)
    }

    /// Write the graph (with its stored values) atomically as JSON.
    pub fn write(&self, path: &Path) -> Result<()> {
        write(self, path)
    }
}
