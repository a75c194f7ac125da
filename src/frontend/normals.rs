//! Normals of the organized cloud: PCA over each cell's grid neighbours.
//!
//! A cell's neighbourhood is itself and the up to eight cells at ring ± 1,
//! column ± 1 whose points lie within a range-dependent gap of its point
//! (so depth discontinuities are not smoothed over). The normal is the
//! eigenvector of the smallest eigenvalue of the neighbourhood covariance,
//! computed without trigonometry or allocation (see [`smallest_eigen`]), and
//! oriented towards the sensor. The surface variation
//! `λ₀ / (λ₀ + λ₁ + λ₂)` (PCL's "curvature") is kept with it; region
//! growing seeds from flat cells first.

use serde::{Deserialize, Serialize};

use super::filter::CellCloud;

/// Neighbourhood settings of the normal estimation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalParams {
    /// A neighbour counts when it is within `max(max_gap, max_gap_ratio ·
    /// range)` metres of the cell's point: fixed part, m.
    pub max_gap: f64,
    /// Range-proportional part of the gap (ring spacing grows with range),
    /// m per m of range.
    pub max_gap_ratio: f64,
    /// Fewest points (the cell included) for a normal: [`MIN_POINTS`].
    #[serde(skip, default = "min_points")]
    pub min_points: usize,
}

/// Fewest points (the cell included) for a normal: the cell and three
/// neighbours of its 3x3 block.
pub const MIN_POINTS: usize = 4;

fn min_points() -> usize {
    MIN_POINTS
}

impl Default for NormalParams {
    /// `[extractor.normals]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("extractor.normals")
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
#[inline]
fn cell_normal(cells: &CellCloud, cell: usize, params: &NormalParams) -> Option<([f32; 3], f32)> {
    let p = cells.xyz(cell);
    let gap = params.gap(cells.range(cell));
    let gap2 = gap * gap;
    // Sums over the neighbourhood, in coordinates relative to the cell's
    // point (well conditioned); the cell itself contributes zeros.
    let (mut k, mut sx, mut sy, mut sz) = (1usize, 0f64, 0f64, 0f64);
    let (mut xx, mut xy, mut xz, mut yy, mut yz, mut zz) = (0f64, 0f64, 0f64, 0f64, 0f64, 0f64);
    cells.for_each_neighbour(cell, |nb| {
        // Empty cells hold NaN, which fails the gap test.
        let q = cells.xyz(nb);
        let r = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        if r[0] * r[0] + r[1] * r[1] + r[2] * r[2] <= gap2 {
            let (x, y, z) = (r[0] as f64, r[1] as f64, r[2] as f64);
            k += 1;
            sx += x;
            sy += y;
            sz += z;
            xx += x * x;
            xy += x * y;
            xz += x * z;
            yy += y * y;
            yz += y * z;
            zz += z * z;
        }
    });
    if k < params.min_points.max(3) {
        return None;
    }
    let inv = 1.0 / k as f64;
    let (mx, my, mz) = (sx * inv, sy * inv, sz * inv);
    let cov = [
        xx - sx * mx,
        xy - sx * my,
        xz - sx * mz,
        yy - sy * my,
        yz - sy * mz,
        zz - sz * mz,
    ];
    let (lambda0, v, trace) = smallest_eigen(&cov)?;
    // Face the sensor: n·p < 0 for the point p seen from the origin.
    let dot = v[0] * p[0] as f64 + v[1] * p[1] as f64 + v[2] * p[2] as f64;
    let s = if dot > 0.0 { -1.0 } else { 1.0 };
    let normal = [(s * v[0]) as f32, (s * v[1]) as f32, (s * v[2]) as f32];
    Some((normal, (lambda0 / trace).max(0.0) as f32))
}

/// Smallest eigenvalue, its unit eigenvector and the trace of the symmetric
/// positive semi-definite 3×3 matrix `[xx xy xz yy yz zz]`, without
/// trigonometry: the smallest root of the characteristic polynomial by
/// Newton's method from 0 (the polynomial is concave and increasing there,
/// so the iterates rise monotonically to the root), the eigenvector as the
/// largest cross product of two rows of `A − λI`. `None` when the matrix is
/// zero or the smallest eigenvalue is (nearly) repeated — a collinear or
/// coincident neighbourhood has no normal.
pub fn smallest_eigen(m: &[f64; 6]) -> Option<(f64, [f64; 3], f64)> {
    let [a00, a01, a02, a11, a12, a22] = *m;
    let trace = a00 + a11 + a22;
    if !(trace > 0.0) || !trace.is_finite() {
        return None;
    }
    // det(A − λI) = −(λ³ − tr λ² + c λ − det).
    let c = a00 * a11 - a01 * a01 + a00 * a22 - a02 * a02 + a11 * a22 - a12 * a12;
    let det = a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a12 * a02)
        + a02 * (a01 * a12 - a11 * a02);
    let mut lambda = 0f64;
    for _ in 0..32 {
        let p = ((lambda - trace) * lambda + c) * lambda - det;
        let dp = (3.0 * lambda - 2.0 * trace) * lambda + c;
        if !(dp > 0.0) {
            break;
        }
        let step = p / dp;
        lambda -= step;
        if !(step.abs() > 1e-14 * trace) {
            break;
        }
    }
    let smallest = lambda.max(0.0);
    // The other two roots: sum s = tr − λ₀, product q = c − λ₀ s.
    let sum = trace - smallest;
    let prod = c - smallest * sum;
    let middle = 0.5 * (sum - (sum * sum - 4.0 * prod).max(0.0).sqrt());
    // A repeated smallest eigenvalue leaves the normal undefined.
    if !(middle - smallest > 1e-4 * trace) {
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
    let (c01, c02, c12) = (cross(&r0, &r1), cross(&r0, &r2), cross(&r1, &r2));
    let (n01, n02, n12) = (norm2(&c01), norm2(&c02), norm2(&c12));
    let (best, n2) = if n01 >= n02 && n01 >= n12 {
        (c01, n01)
    } else if n02 >= n12 {
        (c02, n02)
    } else {
        (c12, n12)
    };
    if !(n2 > 0.0) {
        return None;
    }
    let inv = 1.0 / n2.sqrt();
    Some((
        smallest,
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
