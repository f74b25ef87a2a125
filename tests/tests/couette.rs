//! Sugiyama's oscillating Couette flow with a neo-Hookean layer (μ_s = 0), from rest, against
//! the start-up reference of `../shared/references/oscillating_couette/from_rest/`.

use efsi_core::probes::sample;
use efsi_core::{Scene, Simulation};
use efsi_tests::{interp, orders, read_csv, reference, run_until};
use std::path::Path;

const TIMES: [f64; 4] = [2.0, 2.8, 4.0, 4.8];

/// The errors at one time: max |u − u_ref| at the grid's own u points (the cell-centre rows,
/// the reference interpolated there from its 801 nodes), and over the reference's points with
/// the solution interpolated linearly — across the interface kink, which adds an O(h)
/// interpolation error of its own.
#[derive(Debug, Clone, Copy)]
struct Errors {
    grid: f64,
    sampled: f64,
}

/// [`Errors`] at each of [`TIMES`], for `ny` cells across.
fn couette_errors(ny: usize) -> Vec<Errors> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/oscillating_couette.ron");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.grid.ny = ny;
    // The step shrinks with the cell (the scene's 0.001 at 64 cells), so the order measures the
    // whole scheme (the elastic step is first order in time).
    scene.time.dt_max = Some(0.001 * 64.0 / ny as f64);
    scene.output = Default::default();
    let mut sim =
        Simulation::new(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"));
    let x = 0.5 * (sim.grid.x0 + sim.grid.x1());
    let mut out = Vec::new();
    for t in TIMES {
        run_until(&mut sim, t, |_, _| {});
        let label = efsi_core::run::time_label(t);
        let (h, c) = read_csv(&reference(&format!(
            "oscillating_couette/from_rest/u_profile_t_{label}.csv"
        )));
        let (yi, ui) = (
            h.iter().position(|n| n == "y").unwrap(),
            h.iter().position(|n| n == "u").unwrap(),
        );
        let (ry, ru) = (&c[yi], &c[ui]);
        let sampled = ry
            .iter()
            .zip(ru)
            .map(|(&y, &u)| (sample(&sim.grid, &sim.state, "u", (x, y)) - u).abs())
            .fold(0.0, f64::max);
        let grid = (0..sim.grid.ny as isize)
            .map(|j| {
                let y = sim.grid.y0 + (j as f64 + 0.5) * sim.grid.dy;
                (sim.state.u[(0, j)] - interp(ry, ru, y)).abs()
            })
            .fold(0.0, f64::max);
        out.push(Errors { grid, sampled });
    }
    out
}

/// The target, 0.005 at 64 cells, at the grid's u points; the solution sampled along
/// the reference's 401-point profile (linear interpolation across the interface kink) is held to
/// 0.01 (the peer Eulerian solver misses by 0.025 on this grid).
#[test]
fn couette_64_cells_meets_the_target() {
    let e = couette_errors(64);
    eprintln!("64 cells: errors at t = {TIMES:?}: {e:.5?}");
    for (t, e) in TIMES.iter().zip(&e) {
        assert!(e.grid <= 0.005, "t = {t}: at the grid points {}", e.grid);
        assert!(e.sampled <= 0.01, "t = {t}: sampled {}", e.sampled);
    }
}

/// Observed order over a sequence of grids (Δt ∝ h), of the worst error over the four times, at
/// the grid points.
fn order_test(ns: &[usize]) {
    let errs: Vec<f64> = ns
        .iter()
        .map(|&n| couette_errors(n).iter().map(|e| e.grid).fold(0.0, f64::max))
        .collect();
    let h: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
    let p = orders(&h, &errs);
    eprintln!("cells {ns:?}: errors {errs:?}, orders {p:.3?}");
    assert!(p.iter().all(|&p| p >= 1.0), "orders {p:?}");
}

#[test]
fn couette_converges_at_least_at_first_order() {
    order_test(&[32, 64, 128]);
}

#[test]
#[ignore = "long (≈ 10 min): the issue's 32–256 table; run with --ignored"]
fn couette_order_32_to_256() {
    order_test(&[32, 64, 128, 256]);
}
