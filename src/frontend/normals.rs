//! Normals of the organized cloud: PCA over each cell's grid neighbours.
//!
//! A cell's neighbourhood is itself and the up to eight cells at ring ± 1,
//! column ± 1 whose points lie within a range-dependent gap of its point
//! (so depth discontinuities are not smoothed over). The normal is the
//! eigenvector of the smallest eigenvalue of the neighbourhood covariance,
//! computed in closed form (no iterative eigen solver, no allocation), and
//! oriented towards the sensor. The surface variation
//! `λ₀ / (λ₀ + λ₁ + λ₂)` (PCL's "curvature") is kept with it; region
//! growing seeds from flat cells first.

use serde::{Deserialize, Serialize};

use super::filter::CellCloud;

/// Neighbourhood settings of the normal estimation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NormalParams {
    /// A neighbour counts when it is within `max(max_gap, max_gap_ratio ·
    /// range)` metres of the cell's point: fixed part, m.
    pub max_gap: f64,
    /// Range-proportional part of the gap (ring spacing grows with range).
    pub max_gap_ratio: f64,
    /// Fewest points (the cell included) for a normal.
    pub min_points: usize,
}

impl Default for NormalParams {
    fn default() -> Self {
        Self {
            max_gap: 0.25,
            max_gap_ratio: 0.08,
            min_points: 4,
        }
    }
}

impl NormalParams {
    /// The largest distance (m) between a point at `range` and a neighbour.
    #[inline]
    pub fn gap(&self, range: f32) -> f32 {
        (self.max_gap as f32).max(self.max_gap_ratio as f32 * range)
    }
}

/// A unit normal and surface variation per cell; invalid cells (empty, too
/// few neighbours, collinear neighbourhood) have a NaN curvature.
#[derive(Debug, Clone, Default)]
pub struct OrganizedNormals {
    /// Unit normal per cell, facing the sensor.
    pub normals: Vec<[f32; 3]>,
    /// Surface variation per cell in `[0, 1/3]`; NaN where invalid.
    pub curvature: Vec<f32>,
}

impl OrganizedNormals {
    /// Whether `cell` has a normal.
    #[inline]
    pub fn is_valid(&self, cell: usize) -> bool {
        !self.curvature[cell].is_nan()
    }

    /// Estimate the normals of `cells` into `self`, reusing its buffers.
    pub fn estimate(&mut self, cells: &CellCloud, params: &NormalParams) {
        let n = cells.cells();
        self.normals.clear();
        self.normals.resize(n, [0.0; 3]);
        self.curvature.clear();
        self.curvature.resize(n, f32::NAN);
        for cell in 0..n {
            if cells.point(cell).is_none() {
                continue;
            }
            if let Some((normal, curvature)) = cell_normal(cells, cell, params) {
                self.normals[cell] = normal;
                self.curvature[cell] = curvature;
            }
        }
    }
}

/// Normal and surface variation of one non-empty cell.
fn cell_normal(cells: &CellCloud, cell: usize, params: &NormalParams) -> Option<([f32; 3], f32)> {
    let p = cells.xyz(cell);
    let gap = params.gap(cells.range(cell));
    let gap2 = gap * gap;
    // Coordinates relative to the cell's point (well conditioned in f64).
    let mut pts = [[0f64; 3]; 9];
    let mut k = 1; // pts[0] = the cell itself, at the origin
    for nb in cells.neighbours(cell).into_iter().flatten() {
        if cells.point(nb).is_none() {
            continue;
        }
        let q = cells.xyz(nb);
        let r = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        if r[0] * r[0] + r[1] * r[1] + r[2] * r[2] <= gap2 {
            pts[k] = [r[0] as f64, r[1] as f64, r[2] as f64];
            k += 1;
        }
    }
    if k < params.min_points.max(3) {
        return None;
    }
    let pts = &pts[..k];
    let inv = 1.0 / k as f64;
    let mut mean = [0f64; 3];
    for q in pts {
        for a in 0..3 {
            mean[a] += q[a] * inv;
        }
    }
    let mut cov = [0f64; 6]; // xx xy xz yy yz zz
    for q in pts {
        let (x, y, z) = (q[0] - mean[0], q[1] - mean[1], q[2] - mean[2]);
        cov[0] += x * x;
        cov[1] += x * y;
        cov[2] += x * z;
        cov[3] += y * y;
        cov[4] += y * z;
        cov[5] += z * z;
    }
    let (lambda0, v, trace) = smallest_eigen(&cov)?;
    // Face the sensor: n·p < 0 for the point p seen from the origin.
    let dot = v[0] * p[0] as f64 + v[1] * p[1] as f64 + v[2] * p[2] as f64;
    let s = if dot > 0.0 { -1.0 } else { 1.0 };
    let normal = [(s * v[0]) as f32, (s * v[1]) as f32, (s * v[2]) as f32];
    Some((normal, (lambda0 / trace).max(0.0) as f32))
}

/// Smallest eigenvalue, its unit eigenvector and the trace of the symmetric
/// 3×3 matrix `[xx xy xz yy yz zz]`, in closed form (Smith's trigonometric
/// eigenvalues, the eigenvector as the largest cross product of two rows of
/// `A − λI`). `None` when the matrix is zero or the smallest eigenvalue is
/// (nearly) repeated — a collinear or coincident neighbourhood has no
/// normal.
pub fn smallest_eigen(m: &[f64; 6]) -> Option<(f64, [f64; 3], f64)> {
    let [a00, a01, a02, a11, a12, a22] = *m;
    let trace = a00 + a11 + a22;
    if !(trace > 0.0) || !trace.is_finite() {
        return None;
    }
    let q = trace / 3.0;
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let (b00, b11, b22) = (a00 - q, a11 - q, a22 - q);
    let p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if !(p > 1e-12 * trace) {
        // A multiple of the identity: no preferred direction.
        return None;
    }
    // det(B) / 2 with B = (A - qI) / p.
    let det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02)
        + a02 * (a01 * a12 - b11 * a02);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    let middle = trace - largest - smallest;
    // A repeated smallest eigenvalue leaves the normal undefined.
    if !(middle - smallest > 1e-6 * trace) {
        return None;
    }
    let r0 = [a00 - smallest, a01, a02];
    let r1 = [a01, a11 - smallest, a12];
    let r2 = [a02, a12, a22 - smallest];
    let cross = |a: &[f64; 3], b: &[f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm2 = |v: &[f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let candidates = [cross(&r0, &r1), cross(&r0, &r2), cross(&r1, &r2)];
    let best = candidates
        .iter()
        .max_by(|a, b| norm2(a).total_cmp(&norm2(b)))?;
    let n2 = norm2(best);
    if !(n2 > 0.0) {
        return None;
    }
    let inv = 1.0 / n2.sqrt();
    Some((
        smallest.max(0.0),
        [best[0] * inv, best[1] * inv, best[2] * inv],
        trace,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, SymmetricEigen};

    #[test]
    fn closed_form_matches_nalgebra() {
        let mut rng = crate::rng::SplitMix64::new(3);
        for _ in 0..200 {
            let a = Matrix3::from_fn(|_, _| rng.normal());
            let m = a * a.transpose();
            let packed = [
                m[(0, 0)],
                m[(0, 1)],
                m[(0, 2)],
                m[(1, 1)],
                m[(1, 2)],
                m[(2, 2)],
            ];
            let (l, v, tr) = smallest_eigen(&packed).unwrap();
            let eig = SymmetricEigen::new(m);
            let k = eig.eigenvalues.imin();
            assert!(
                (l - eig.eigenvalues[k]).abs() < 1e-9 * tr,
                "{l} vs {}",
                eig.eigenvalues[k]
            );
            let e = eig.eigenvectors.column(k);
            let dot = (v[0] * e[0] + v[1] * e[1] + v[2] * e[2]).abs();
            assert!(dot > 1.0 - 1e-6, "{dot}");
        }
    }

    #[test]
    fn degenerate_matrices_have_no_normal() {
        assert!(smallest_eigen(&[0.0; 6]).is_none());
        assert!(smallest_eigen(&[1.0, 0.0, 0.0, 1.0, 0.0, 1.0]).is_none());
        // Collinear points: a rank-1 scatter along x.
        assert!(smallest_eigen(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
        // A flat patch in the xy plane: the normal is z.
        let (l, v, _) = smallest_eigen(&[2.0, 0.1, 0.0, 1.0, 0.0, 0.0]).unwrap();
        assert!(l.abs() < 1e-12 && v[2].abs() > 1.0 - 1e-12);
    }
}
