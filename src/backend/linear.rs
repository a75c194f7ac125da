//! Sparse normal equations `H δ = −g` (`H = JᵀJ`, `g = Jᵀr` on whitened,
//! reweighted rows) and their solution with faer's sparse Cholesky.
//!
//! * The block pattern of `H` (lower triangle, CSC) is computed **once**
//!   from the factors' keys; each factor owns a precomputed run of value
//!   slots, so assembly is a scatter with no search and no allocation.
//! * Jacobi scaling: the system is solved as `(D H D) y = −D g`, `δ = D y`
//!   with `D = diag(H)^{-½}`, so far planes (large `d`, lever arms) and
//!   metres vs radians do not ruin the conditioning. Levenberg–Marquardt's
//!   `λ·diag(H)` damping becomes `λ·I` in the scaled system.
//! * The symbolic Cholesky (AMD ordering, elimination tree,
//!   supernodal/simplicial choice) is computed once; every iteration reuses
//!   it, the numeric factor buffer and the workspace (sequential, hence
//!   deterministic).

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use super::factors::{Factor, Linearization};
use super::graph::FactorGraph;
use super::ordering::{Ordering, FIXED};
use super::variables::Values;
use crate::{Error, Result};

/// Why a linear solve failed.
#[derive(Debug)]
pub enum LinearError {
    /// `H (+ λ D)` is not (numerically) positive definite: Cholesky met a
    /// non-positive pivot, or the scaled step is more than
    /// [`SINGULAR_GROWTH`] times the scaled gradient, which means a scaled
    /// eigenvalue below `1 / SINGULAR_GROWTH` (an unobservable direction,
    /// gauge freedom, or too little damping).
    NotPositiveDefinite,
    /// Anything else (no information on a variable, non-finite numbers).
    Other(Error),
}

impl From<Error> for LinearError {
    fn from(e: Error) -> Self {
        LinearError::Other(e)
    }
}

/// Fill-reducing ordering computed on the block (variable) graph and
/// expanded to scalar columns, keeping each variable's columns together:
/// AMD on `#variables` nodes instead of `#unknowns` is several times cheaper
/// and gives the supernodal factorisation whole variable blocks.
fn block_amd(
    rows_of: &[Vec<u32>],
    offsets: &[usize],
    dims: &[usize],
) -> Result<(Vec<usize>, Vec<usize>)> {
    let nvars = rows_of.len();
    let mut col_ptr = Vec::with_capacity(nvars + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0usize);
    for rows in rows_of {
        row_idx.extend(rows.iter().map(|&r| r as usize));
        col_ptr.push(row_idx.len());
    }
    let nnz = row_idx.len();
    let blocks = SymbolicSparseColMat::<usize>::new_checked(nvars, nvars, col_ptr, None, row_idx);
    let mut bperm = vec![0usize; nvars];
    let mut bperm_inv = vec![0usize; nvars];
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(nvars, nnz));
    amd::order(
        &mut bperm,
        &mut bperm_inv,
        blocks.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| Error::Input(format!("AMD ordering failed: {e:?}")))?;
    let n: usize = dims.iter().sum();
    let mut perm = Vec::with_capacity(n);
    for &v in &bperm {
        perm.extend(offsets[v]..offsets[v] + dims[v]);
    }
    let mut perm_inv = vec![0usize; n];
    for (new, &old) in perm.iter().enumerate() {
        perm_inv[old] = new;
    }
    Ok((perm, perm_inv))
}

/// Largest ratio `‖y‖∞ / ‖D g‖∞` of the scaled system accepted as a real
/// solution. The scaled `H` has a unit diagonal, so its largest eigenvalue is
/// at least 1 and a larger ratio proves a condition number above this bound:
/// a tiny positive pivot in an exactly singular direction, which Cholesky
/// does not report, is caught here instead of returning a wild step.
pub const SINGULAR_GROWTH: f64 = 1e10;

/// Wall-clock seconds spent in the last assembly / factorisation / solve.
#[derive(Debug, Clone, Copy, Default)]
pub struct LinearTimings {
    /// Linearising every factor and scattering into `H` and `g`.
    pub assembly: f64,
    /// Scaling, damping and the numeric Cholesky factorisation.
    pub factorization: f64,
    /// Triangular solves and unscaling.
    pub solve: f64,
}

/// The sparse normal equations of one graph, reusable across iterations.
pub struct LinearSystem {
    ordering: Ordering,
    /// Per factor: the variable index of each key ([`FIXED`] if fixed).
    factor_vars: Vec<[u32; 2]>,
    /// Per factor: first entry in `slots`.
    slot_base: Vec<u32>,
    /// Value index in `h` of every scattered entry, in scatter order.
    slots: Vec<u32>,
    symbolic: SymbolicSparseColMat<usize>,
    /// Column of every stored value of `h`.
    value_col: Vec<u32>,
    /// Value index of every diagonal entry.
    diag: Vec<usize>,
    cholesky: SymbolicCholesky<usize>,
    h: Vec<f64>,
    g: Vec<f64>,
    scale: Vec<f64>,
    h_scaled: Vec<f64>,
    l_values: Vec<f64>,
    mem: MemBuffer,
    step: Vec<f64>,
    lin: Linearization,
    /// Timings of the last [`LinearSystem::assemble`] and
    /// [`LinearSystem::solve`].
    pub timings: LinearTimings,
}

impl LinearSystem {
    /// Build the pattern and the symbolic factorisation for `graph` with the
    /// variables in `ordering` (the others are fixed).
    pub fn new(graph: &FactorGraph, ordering: Ordering) -> Result<Self> {
        let nvars = ordering.keys.len();
        if nvars == 0 {
            return Err(Error::Input("the graph has no free variable".into()));
        }
        let dims: Vec<usize> = ordering.keys.iter().map(|k| k.dim()).collect();
        let factor_vars: Vec<[u32; 2]> = graph
            .factors
            .iter()
            .map(|f| {
                let keys = f.factor.keys();
                let mut v = [FIXED; 2];
                for (slot, &k) in v.iter_mut().zip(keys) {
                    *slot = ordering.var(k);
                }
                v
            })
            .collect();

        // Block pattern: row blocks of each block column (lower triangle).
        let mut rows_of: Vec<Vec<u32>> = (0..nvars as u32).map(|j| vec![j]).collect();
        for (f, vars) in graph.factors.iter().zip(&factor_vars) {
            let n = f.factor.keys().len();
            if n == 2 && vars[0] != FIXED && vars[1] != FIXED {
                if vars[0] == vars[1] {
                    return Err(Error::Input(format!(
                        "{} factor uses {} twice",
                        f.factor.type_name(),
                        ordering.keys[vars[0] as usize]
                    )));
                }
                let (hi, lo) = (vars[0].max(vars[1]), vars[0].min(vars[1]));
                rows_of[lo as usize].push(hi);
            }
        }
        for r in &mut rows_of {
            r.sort_unstable();
            r.dedup();
        }

        // CSC structure.
        let n = ordering.dim;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut value_col = Vec::new();
        col_ptr.push(0usize);
        for (j, rows) in rows_of.iter().enumerate() {
            let (oj, dj) = (ordering.offsets[j], dims[j]);
            for c in 0..dj {
                for &i in rows {
                    let i = i as usize;
                    let (oi, di) = (ordering.offsets[i], dims[i]);
                    let start = if i == j { c } else { 0 };
                    for r in start..di {
                        row_idx.push(oi + r);
                        value_col.push((oj + c) as u32);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let position = |row: usize, col: usize| -> usize {
            let (a, b) = (col_ptr[col], col_ptr[col + 1]);
            a + row_idx[a..b]
                .binary_search(&row)
                .expect("entry is in the pattern by construction")
        };
        let diag: Vec<usize> = (0..n).map(|c| position(c, c)).collect();

        // Value slots of every factor, in the order `assemble` visits them.
        let mut slot_base = Vec::with_capacity(graph.factors.len());
        let mut slots: Vec<u32> = Vec::new();
        for (f, vars) in graph.factors.iter().zip(&factor_vars) {
            slot_base.push(slots.len() as u32);
            let nk = f.factor.keys().len();
            for a in 0..nk {
                for b in 0..=a {
                    let (va, vb) = (vars[a], vars[b]);
                    if va == FIXED || vb == FIXED {
                        continue;
                    }
                    let (row_v, col_v) = (va.max(vb) as usize, va.min(vb) as usize);
                    let (orow, drow) = (ordering.offsets[row_v], dims[row_v]);
                    let (ocol, dcol) = (ordering.offsets[col_v], dims[col_v]);
                    for c in 0..dcol {
                        let start = if row_v == col_v { c } else { 0 };
                        for r in start..drow {
                            slots.push(position(orow + r, ocol + c) as u32);
                        }
                    }
                }
            }
        }

        let nnz = row_idx.len();
        let symbolic = SymbolicSparseColMat::<usize>::new_checked(n, n, col_ptr, None, row_idx);
        let (perm, perm_inv) = block_amd(&rows_of, &ordering.offsets, &dims)?;
        let cholesky = factorize_symbolic_cholesky(
            symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&perm, &perm_inv, n)),
            Default::default(),
        )
        .map_err(|e| Error::Input(format!("symbolic Cholesky failed: {e:?}")))?;
        let scratch = cholesky
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(cholesky.solve_in_place_scratch::<f64>(1, Par::Seq));
        let l_values = vec![0.0; cholesky.len_val()];
        Ok(Self {
            ordering,
            factor_vars,
            slot_base,
            slots,
            symbolic,
            value_col,
            diag,
            cholesky,
            h: vec![0.0; nnz],
            g: vec![0.0; n],
            scale: vec![0.0; n],
            h_scaled: vec![0.0; nnz],
            l_values,
            mem: MemBuffer::new(scratch),
            step: vec![0.0; n],
            lin: Linearization::default(),
            timings: LinearTimings::default(),
        })
    }

    /// The variable layout.
    pub fn ordering(&self) -> &Ordering {
        &self.ordering
    }

    /// Number of stored entries of `H` (lower triangle).
    pub fn nnz_h(&self) -> usize {
        self.h.len()
    }

    /// Number of stored values of the Cholesky factor `L`.
    pub fn nnz_factor(&self) -> usize {
        self.cholesky.len_val()
    }

    /// Linearise every factor at `values` and fill `H` and `g`; returns the
    /// cost `½ Σ ρ(s)` at `values`.
    pub fn assemble(&mut self, graph: &FactorGraph, values: &Values) -> Result<f64> {
        let t0 = Instant::now();
        self.h.fill(0.0);
        self.g.fill(0.0);
        let offsets = &self.ordering.offsets;
        let mut cost = 0.0;
        for (fi, f) in graph.factors.iter().enumerate() {
            cost += f.linearize(values, &mut self.lin)?;
            let lin = &self.lin;
            let vars = self.factor_vars[fi];
            let keys = f.factor.keys();
            let m = lin.dim;
            for (a, &va) in vars.iter().enumerate().take(keys.len()) {
                if va == FIXED {
                    continue;
                }
                let ja = &lin.jacobians[a];
                let off = offsets[va as usize];
                for r in 0..keys[a].dim() {
                    let mut s = 0.0;
                    for k in 0..m {
                        s += ja[(k, r)] * lin.residual[k];
                    }
                    self.g[off + r] += s;
                }
            }
            let mut slot = self.slot_base[fi] as usize;
            for a in 0..keys.len() {
                for b in 0..=a {
                    let (va, vb) = (vars[a], vars[b]);
                    if va == FIXED || vb == FIXED {
                        continue;
                    }
                    // Block (row var, col var) with row ≥ col: J_rowᵀ J_col.
                    let (ra, cb) = if va >= vb { (a, b) } else { (b, a) };
                    let (jr, jc) = (&lin.jacobians[ra], &lin.jacobians[cb]);
                    let (drow, dcol) = (keys[ra].dim(), keys[cb].dim());
                    let diagonal = a == b;
                    for c in 0..dcol {
                        let start = if diagonal { c } else { 0 };
                        for r in start..drow {
                            let mut s = 0.0;
                            for k in 0..m {
                                s += jr[(k, r)] * jc[(k, c)];
                            }
                            self.h[self.slots[slot] as usize] += s;
                            slot += 1;
                        }
                    }
                }
            }
        }
        self.timings.assembly = t0.elapsed().as_secs_f64();
        if !cost.is_finite() {
            return Err(Error::Input("the graph's cost is not finite".into()));
        }
        Ok(cost)
    }

    /// The gradient `g = Jᵀ r` of the last assembly.
    pub fn gradient(&self) -> &[f64] {
        &self.g
    }

    /// `H_ii` of the last assembly.
    pub fn diagonal(&self, i: usize) -> f64 {
        self.h[self.diag[i]]
    }

    /// Solve `(H + λ diag(H)) δ = −g` for the last assembly; returns `δ`.
    pub fn solve(&mut self, lambda: f64) -> std::result::Result<&[f64], LinearError> {
        let t0 = Instant::now();
        for (i, &d) in self.diag.iter().enumerate() {
            let hii = self.h[d];
            if !(hii > 0.0) || !hii.is_finite() {
                let key = self.variable_of(i);
                return Err(LinearError::Other(Error::Input(format!(
                    "variable {key} has no information (H[{i},{i}] = {hii}): no factor \
                     constrains it; remove it, add a prior or fix it"
                ))));
            }
            self.scale[i] = 1.0 / hii.sqrt();
        }
        let rows = self.symbolic.row_idx();
        for (((out, &h), &row), &col) in self
            .h_scaled
            .iter_mut()
            .zip(&self.h)
            .zip(rows)
            .zip(&self.value_col)
        {
            *out = h * self.scale[row] * self.scale[col as usize];
        }
        for &d in &self.diag {
            self.h_scaled[d] = 1.0 + lambda;
        }
        let a = SparseColMatRef::new(self.symbolic.as_ref(), &self.h_scaled);
        let llt = self.cholesky.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            a,
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        let llt = match llt {
            Ok(l) => l,
            // The only numeric failure is a non-positive pivot.
            Err(_) => return Err(LinearError::NotPositiveDefinite),
        };
        let t1 = Instant::now();
        let n = self.step.len();
        let mut rhs_max = 0.0f64;
        for i in 0..n {
            self.step[i] = -self.g[i] * self.scale[i];
            rhs_max = rhs_max.max(self.step[i].abs());
        }
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.step, n, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        let step_max = self.step.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let singular = !(step_max <= SINGULAR_GROWTH * rhs_max);
        for i in 0..n {
            self.step[i] *= self.scale[i];
        }
        let t2 = Instant::now();
        self.timings.factorization = (t1 - t0).as_secs_f64();
        self.timings.solve = (t2 - t1).as_secs_f64();
        if singular || !self.step.iter().all(|v| v.is_finite()) {
            return Err(LinearError::NotPositiveDefinite);
        }
        Ok(&self.step)
    }

    /// The key owning column `col`.
    pub fn variable_of(&self, col: usize) -> super::variables::Key {
        let o = &self.ordering.offsets;
        let v = o.partition_point(|&off| off <= col) - 1;
        self.ordering.keys[v]
    }

    /// `values` moved by the step `δ` (one retraction per free variable).
    pub fn retract(&self, values: &Values, step: &[f64]) -> Result<Values> {
        let mut out = values.clone();
        for (key, &off) in self.ordering.keys.iter().zip(&self.ordering.offsets) {
            out.retract_key(*key, &step[off..off + key.dim()])?;
        }
        Ok(out)
    }
}
