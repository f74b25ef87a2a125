//! The pressure projection: the divergence postcondition over whole runs, and convergence of
//! the variable-density Poisson solve at density ratio 1e4 (planar and axisymmetric).

use efsi_core::operators::max_abs_div;
use efsi_stages::projection::Projection;
use efsi_tests::{run_until, sim, sim_with};

#[test]
fn every_projection_leaves_divergence_below_tolerance() {
    let text = r#"Scene(
        name: "cavity",
        domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 24, ny: 24),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        numerics: (projection: (tolerance: 1e-10)),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    )"#;
    let mut s = sim(text);
    let mut worst = 0.0f64;
    let mut steps = 0;
    run_until(&mut s, 1.0, |s, dt| {
        worst = worst.max(max_abs_div(&s.grid, &s.state.velocity()) * dt);
        steps += 1;
    });
    eprintln!("{steps} steps, worst max|∇·u|·Δt = {worst:.3e}");
    assert!(worst <= 1e-10, "{worst:e}");
}

fn dense_disk(geometry: &str, x: (f64, f64), xmin: &str) -> String {
    format!(
        r#"Scene(
        name: "disk",
        geometry: {geometry},
        domain: (x: {x:?}, y: (0.0, 1.0)),
        grid: (nx: 64, ny: 64),
        time: (end: 1.0, fixed_dt: 0.01),
        fluid: (density: 1.0, viscosity: 0.0),
        numerics: (projection: (tolerance: 1e-10, max_iterations: 20000)),
        boundaries: (x_min: {xmin}, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    )"#
    )
}

/// A disk (sphere) 1e4 times denser than the fluid, and a divergent velocity field: one
/// projection must converge and leave max|∇·u|·Δt ≤ 1e-10.
#[test]
fn variable_density_poisson_converges_at_density_ratio_1e4() {
    for (geometry, x, xmin, centre) in [
        ("Planar", (0.0, 1.0), "NoSlip", 0.5),
        ("Axisymmetric", (0.0, 1.0), "Axis", 0.0),
    ] {
        let mut s = sim_with(&dense_disk(geometry, x, xmin), &[&Projection]).unwrap();
        let g = s.grid.clone();
        for j in -2..(g.ny as isize + 2) {
            for i in -2..(g.nx as isize + 2) {
                let (xc, yc) = (g.xc(i), g.yc(j));
                let inside = (xc - centre).hypot(yc - 0.5) < 0.25;
                s.state.rho[(i, j)] = if inside { 1e4 } else { 1.0 };
            }
        }
        for j in 0..g.ny as isize {
            for i in 0..=g.nx as isize {
                s.state.u[(i, j)] = (7.0 * g.xf(i)).sin() * (3.0 * g.yc(j)).cos();
            }
        }
        for j in 0..=g.ny as isize {
            for i in 0..g.nx as isize {
                s.state.v[(i, j)] = (5.0 * g.xc(i) * g.yf(j)).cos();
            }
        }
        s.bc.fill_velocity(&g, &mut s.state.u, &mut s.state.v, 0.0, false);
        s.step(0.01).unwrap();
        let stats = s.pipeline().last_stats()[0].1.solve.unwrap();
        let d = max_abs_div(&g, &s.state.velocity()) * 0.01;
        eprintln!(
            "{geometry}: density ratio 1e4, {} PCG iterations, max|∇·u|·Δt = {d:.2e}",
            stats.iterations
        );
        assert!(stats.converged);
        assert!(d <= 1e-10, "{d:e}");
    }
}
