//! Per-iteration cost of the sparse back-end on synthetic pose-plane graphs.
//!
//! Run: `cargo bench --bench backend` (add `-- --quick` to skip 10,000
//! poses). For 100, 1,000 and 10,000 poses with 10 plane observations per
//! pose (plane-to-plane and point-to-plane), it times the one-off symbolic
//! setup (pattern, AMD, symbolic Cholesky) and, per Gauss–Newton iteration,
//! the assembly (linearise + scatter), the numeric factorisation and the
//! triangular solves. Per-iteration figures are the median over 5
//! iterations at the same linearisation point.

use std::time::Instant;

use specular::backend::linear::LinearSystem;
use specular::backend::ordering::Ordering;
use specular::backend::synthetic::{synthetic, SyntheticParams};
use specular::backend::PlaneFactorKind;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).expect("finite timings"));
    v[v.len() / 2]
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let sizes: &[usize] = if quick {
        &[100, 1000]
    } else {
        &[100, 1000, 10_000]
    };
    println!(
        "| factor | poses | unknowns | factors | nnz(H) | nnz(L) | setup ms | assembly ms | factorisation ms | solve ms | total ms/iter | µs/iter/pose |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for factor in [PlaneFactorKind::PlaneToPlane, PlaneFactorKind::PointToPlane] {
        for &n in sizes {
            let s = synthetic(&SyntheticParams {
                poses: n,
                factor,
                seed: 1,
                ..SyntheticParams::default()
            })
            .expect("synthetic graph");
            let g = &s.graph;
            let t0 = Instant::now();
            let ordering = Ordering::new(g, &g.effective_fixed());
            let mut sys = LinearSystem::new(g, ordering).expect("linear system");
            let setup = t0.elapsed().as_secs_f64();
            let (mut asm, mut fact, mut solve, mut total) = (vec![], vec![], vec![], vec![]);
            for _ in 0..5 {
                let t = Instant::now();
                sys.assemble(g, &g.values).expect("assemble");
                let a = sys.timings.assembly;
                sys.solve(0.0).map_err(|_| "singular").expect("solve");
                total.push(t.elapsed().as_secs_f64());
                asm.push(a);
                fact.push(sys.timings.factorization);
                solve.push(sys.timings.solve);
            }
            let tot = median(total);
            println!(
                "| {} | {} | {} | {} | {} | {} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |",
                match factor {
                    PlaneFactorKind::PlaneToPlane => "plane",
                    PlaneFactorKind::PointToPlane => "point",
                },
                n,
                sys.ordering().dim,
                g.factors.len(),
                sys.nnz_h(),
                sys.nnz_factor(),
                setup * 1e3,
                median(asm) * 1e3,
                median(fact) * 1e3,
                median(solve) * 1e3,
                tot * 1e3,
                tot * 1e6 / n as f64,
            );
        }
    }
}
