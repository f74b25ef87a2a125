//! Stress + tangent evaluation of a law, through the plugin ABI versus compiled in, in batches
//! of 4096 cells (the size the elastic stage uses for a 64² grid), and one cell per call.
//!
//! `cargo bench -p efsi-laws-host --bench law`; figure of merit: ns per cell.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use efsi_laws_host::{ConstitutiveLaw, NeoHookeanReference, Sym, Tangent, load_law};
use std::hint::black_box;

fn states(n: usize) -> Vec<Sym> {
    (0..n)
        .map(|k| {
            let s = (k as f64 * 0.618).fract();
            [1.0 + 0.2 * s, 1.0 - 0.1 * s, 1.0, 0.3 * s - 0.1]
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let parameters = [("G".to_string(), 1e5)].into_iter().collect();
    let plugin = load_law("neo_hookean", &parameters, std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let native = NeoHookeanReference { g: 1e5 };
    let n = 4096;
    let b = states(n);
    let mut tau = vec![[0.0; 4]; n];
    let mut jac: Vec<Tangent> = vec![[0.0; 16]; n];
    let mut group = c.benchmark_group("neo_hookean_stress_and_tangent");
    group.throughput(Throughput::Elements(n as u64));
    let laws: [(&str, &dyn ConstitutiveLaw); 2] = [
        ("plugin_batch_4096", &plugin),
        ("compiled_in_batch_4096", &native),
    ];
    for (name, law) in laws {
        group.bench_function(name, |bch| {
            bch.iter(|| {
                law.evaluate(black_box(&b), &mut tau, Some(&mut jac))
                    .unwrap()
            });
        });
    }
    for (name, law) in [
        ("plugin_one_call_per_cell", &plugin as &dyn ConstitutiveLaw),
        ("compiled_in_one_call_per_cell", &native),
    ] {
        group.bench_function(name, |bch| {
            bch.iter(|| {
                for k in 0..n {
                    law.evaluate(
                        black_box(&b[k..k + 1]),
                        &mut tau[k..k + 1],
                        Some(&mut jac[k..k + 1]),
                    )
                    .unwrap();
                }
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
