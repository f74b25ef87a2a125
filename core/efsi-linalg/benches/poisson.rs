//! Kernels of the pressure solve on the variable-density Poisson matrix of a heavy disk
//! (density ratio 1000) in a closed box: the five-point product, one multigrid cycle
//! (`multigrid_w_cycle`: W on the two finest levels, V below), one IC(0) application, the
//! multigrid setup, and whole MG-PCG and IC-PCG solves to 1e-10, at 128² and 256², on the
//! current rayon pool (`RAYON_NUM_THREADS=1` for one thread).
//!
//! `cargo bench -p efsi-linalg --bench poisson`; figure of merit: time per call (per cell with
//! the throughput shown).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use efsi_linalg::{IncompleteCholesky, Multigrid, Pcg, Preconditioner, Stencil5};
use std::hint::black_box;

/// `Σ_f (h/(ρ_f h))(p_C − p_F)` on the unit square, a disk of density 1000 in fluid of density 1.
fn matrix(n: usize) -> Stencil5 {
    let h = 1.0 / n as f64;
    let rho = |i: usize, j: usize| {
        let (x, y) = ((i as f64 + 0.5) * h - 0.5, (j as f64 + 0.5) * h - 0.6);
        if x * x + y * y < 0.04 { 1000.0 } else { 1.0 }
    };
    let mut a = Stencil5::new(n, n, false, false);
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            a.east[k] = if i + 1 < n {
                2.0 / (rho(i, j) + rho(i + 1, j))
            } else {
                0.0
            };
            a.north[k] = if j + 1 < n {
                2.0 / (rho(i, j) + rho(i, j + 1))
            } else {
                0.0
            };
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let w = if i > 0 { a.east[k - 1] } else { 0.0 };
            let s = if j > 0 { a.north[k - n] } else { 0.0 };
            a.diag[k] = a.east[k] + a.north[k] + w + s;
        }
    }
    a
}

fn rhs(n: usize) -> Vec<f64> {
    let mut b: Vec<f64> = (0..n * n)
        .map(|k| ((k * 7919) % 1009) as f64 / 1009.0)
        .collect();
    let mean = b.iter().sum::<f64>() / b.len() as f64;
    b.iter_mut().for_each(|v| *v -= mean);
    b
}

fn bench(c: &mut Criterion) {
    for n in [128, 256] {
        let mut a = matrix(n);
        let b = rhs(n);
        let mut y = vec![0.0; n * n];
        let mut mg = Multigrid::new(2);
        mg.setup(&a);
        let mut ic = IncompleteCholesky::new();
        ic.factor(&a);
        let mut g = c.benchmark_group(format!("poisson_{n}"));
        g.throughput(Throughput::Elements((n * n) as u64));
        g.bench_function("stencil5_mul", |bch| {
            bch.iter(|| a.mul(black_box(&b), &mut y))
        });
        g.bench_function("multigrid_w_cycle", |bch| {
            bch.iter(|| mg.apply(black_box(&b), &mut y))
        });
        g.bench_function("ic0_apply", |bch| {
            bch.iter(|| ic.apply(black_box(&b), &mut y))
        });
        g.bench_function("multigrid_setup", |bch| {
            bch.iter(|| mg.setup(black_box(&a)))
        });
        let maxabs = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-10 * maxabs(&b);
        let mut pcg = Pcg::new(n * n);
        g.sample_size(10);
        g.bench_function("mg_pcg_solve", |bch| {
            bch.iter(|| {
                y.fill(0.0);
                pcg.solve(&mut a, &mg, &b, &mut y, tol, 1000, maxabs)
            })
        });
        g.bench_function("ic_pcg_solve", |bch| {
            bch.iter(|| {
                y.fill(0.0);
                pcg.solve(&mut a, &ic, &b, &mut y, tol, 20000, maxabs)
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
