//! Criterion benchmarks of the hot kernels: one VOF PLIC step (the VOF stage alone, without
//! Navier–Stokes) at 256² on the single-vortex field, planar and axisymmetric.
//!
//! `cargo bench -p efsi-stages --bench kernels`; the figure of merit is ns per cell-step
//! (time per iteration / 65 536 cells).

use criterion::{Criterion, criterion_group, criterion_main};
use efsi_core::{Field, Geometry, Grid};
use efsi_stages::vof::{Shape, fill_fraction};
use efsi_stages::vof::{VofAdvector, VofBoundaries};
use std::f64::consts::PI;
use std::hint::black_box;

fn vortex_setup(geometry: Geometry, n: usize) -> (Grid, Field, Field, Field) {
    let grid = Grid::new(geometry, n, n, (0.0, 1.0), (0.0, 1.0));
    let mut phi = Field::zeros(&grid);
    let center = if geometry == Geometry::Axisymmetric {
        (0.0, 0.5)
    } else {
        (0.5, 0.75)
    };
    fill_fraction(
        &grid,
        &Shape::Disk {
            center,
            radius: 0.15,
        },
        &mut phi,
    );
    let (mut u, mut v) = (Field::zeros(&grid), Field::zeros(&grid));
    // Rider–Kothe single vortex (planar) or a Stokes-stream-function vortex (axisymmetric),
    // sampled at corners so the discrete field is solenoidal.
    let psi = |x: f64, y: f64| (PI * x).sin().powi(2) * (PI * y).sin().powi(2) / PI;
    let p = |i: isize, j: isize| psi(grid.xf(i), grid.yf(j));
    for j in 0..n as isize {
        for i in 0..=n as isize {
            let rf = grid.metric.rx(i);
            let d = -(p(i, j + 1) - p(i, j)) / grid.dy;
            u[(i, j)] = if geometry == Geometry::Planar {
                d
            } else if rf > 0.0 {
                d / rf
            } else {
                0.0
            };
        }
    }
    for j in 0..=n as isize {
        for i in 0..n as isize {
            v[(i, j)] = (p(i + 1, j) - p(i, j)) / grid.dx / grid.metric.rc(i);
        }
    }
    (grid, phi, u, v)
}

fn vof_step(c: &mut Criterion) {
    for (name, geometry) in [
        ("vof_step_256_planar", Geometry::Planar),
        ("vof_step_256_axisymmetric", Geometry::Axisymmetric),
    ] {
        let (grid, phi0, u, v) = vortex_setup(geometry, 256);
        let mut adv = VofAdvector::new(&grid, VofBoundaries::closed());
        let umax = u
            .max_abs(efsi_core::Stagger::XFace, 256, 256)
            .max(v.max_abs(efsi_core::Stagger::YFace, 256, 256));
        let dt = 0.25 * grid.dx / umax;
        let mut phi = phi0.clone();
        let mut k = 0u64;
        c.bench_function(name, |b| {
            b.iter(|| {
                k += 1;
                if k.is_multiple_of(512) {
                    phi.copy_from(&phi0);
                }
                black_box(adv.step(&grid, &mut phi, &[&u, &v], dt, k));
            })
        });
    }
}

criterion_group!(benches, vof_step);
criterion_main!(benches);
